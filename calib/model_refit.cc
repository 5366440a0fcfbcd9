#include "calib/model_refit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace hovs::calib {
namespace {

// Pixel residual of one grid pixel's ray through a generic model (the tools' frame).
// The ray turned by gamma about the optical axis (the same axis in both frames).
template <class T>
Vec3<T> AboutAxis(const Vec3d& ray, const T& gamma) {
  using std::cos;
  using std::sin;
  const T c = cos(gamma), s = sin(gamma);
  return Vec3<T>(c * ray.x() - s * ray.y(), s * ray.x() + c * ray.y(), T(ray.z()));
}

template <int N>
struct GenericResidual {
  GenericKind kind;
  Vec3d ray;  // tools' frame
  Vec2d px;
  template <class T>
  bool operator()(const T* p, const T* gamma, T* r) const {
    GenericModel<T> m;
    m.kind = kind;
    for (int k = 0; k < N; ++k) m.p[k] = p[k];
    Vec2<T> uv;
    if (!m.ImgFromCam(AboutAxis(ray, gamma[0]), &uv)) return false;
    r[0] = uv(0) - T(px.x()), r[1] = uv(1) - T(px.y());
    return true;
  }
};

// The same through the unified model with radial-tangential distortion (hovs' mirror frame).
struct UnifiedResidual {
  Vec3d ray;  // mirror frame
  Vec2d px;
  template <class T>
  bool operator()(const T* p, const T* gamma, T* r) const {
    UnifiedModel<T> m;
    m.xi = p[0], m.fx = p[1], m.fy = p[2], m.cx = p[3], m.cy = p[4];
    m.distortion = {p[5], p[6], p[7], p[8]};
    Vec2<T> uv;
    if (!m.ImgFromCam(AboutAxis(ray, gamma[0]), &uv)) return false;
    r[0] = uv(0) - T(px.x()), r[1] = uv(1) - T(px.y());
    return true;
  }
};

struct Sample {
  Vec2d px;
  Vec3d mirror;  // unit bearing, hovs' mirror frame
};

}  // namespace

void RefitOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(kind == "ds" || kind == "eucm" || kind == "kb" || kind == "omni", where, "unknown model '", kind,
               "' (known: ds, eucm, kb, omni)");
  HOVS_REQUIRE(grid_step_px >= 0 && grid_step_px <= 10000, where, "the grid step must be 0 (automatic) to 10000 px");
  HOVS_REQUIRE(max_iterations >= 1 && max_iterations <= 10000, where, "max_iterations must be in 1..10000");
}

Refit RefitModel(const AnyModel& source, const RefitOptions& o) {
  o.Check("model refit");
  const int step = o.grid_step_px > 0 ? o.grid_step_px : std::max(1, source.width() / 60);
  std::vector<Sample> samples;
  for (int v = 0; v < source.height(); v += step)
    for (int u = 0; u < source.width(); u += step) {
      Sample s{Vec2d(u, v), Vec3d::Zero()};
      if (source.MirrorFromImg(s.px, &s.mirror)) samples.push_back({s.px, s.mirror.normalized()});
    }
  HOVS_REQUIRE(samples.size() >= 50, "model refit", "the source model's domain covers only ", samples.size(),
               " grid pixels (at least 50 needed)");
  Refit out;
  out.kind = o.kind;
  out.pixels = samples.size();
  // The start: the centre where the ray is nearest the axis, the focal length of a parabolic mirror
  // (r = 2 f tan(theta / 2)) through the median of the samples.
  const Sample* axis = &samples[0];
  for (const auto& s : samples) {
    if (OmniFromMirror(s.mirror).z() > OmniFromMirror(axis->mirror).z()) axis = &s;
    out.field_deg =
        std::max(out.field_deg, std::acos(std::clamp(OmniFromMirror(s.mirror).z(), -1.0, 1.0)) * 180 / M_PI);
  }
  const Vec2d c = axis->px;
  std::vector<double> f;
  for (const auto& s : samples) {
    const double th = std::acos(std::clamp(OmniFromMirror(s.mirror).z(), -1.0, 1.0)), rho = (s.px - c).norm();
    if (th > 0.05 && rho > 1) f.push_back(rho / (2 * std::tan(0.5 * th)));
  }
  HOVS_REQUIRE(!f.empty(), "model refit", "the source's domain has no ray off its axis");
  std::nth_element(f.begin(), f.begin() + f.size() / 2, f.end());
  const double f0 = f[f.size() / 2];
  ceres::Problem problem;
  std::vector<double> p;
  double gamma = 0;  // the refit's frame: the source's turned about the optical axis (e.g. an affine's rotation)
  GenericKind gk = GenericKind::kDoubleSphere;
  if (o.kind == "omni") {
    p = {1.0, 2 * f0, 2 * f0, c.x(), c.y(), 0, 0, 0, 0};
    for (const auto& s : samples)
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<UnifiedResidual, 2, 9, 1>(new UnifiedResidual{s.mirror, s.px}), nullptr,
          p.data(), &gamma);
    problem.SetParameterLowerBound(p.data(), 0, 0.0);
    out.names = {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};
  } else {
    gk = o.kind == "ds"     ? GenericKind::kDoubleSphere
         : o.kind == "eucm" ? GenericKind::kEucm
                            : GenericKind::kKannalaBrandt;
    if (gk == GenericKind::kDoubleSphere) {
      p = {0.0, 0.5, f0, f0, c.x(), c.y()};
      out.names = {"xi", "alpha", "fx", "fy", "cx", "cy"};
    } else if (gk == GenericKind::kEucm) {
      p = {0.5, 1.0, f0, f0, c.x(), c.y()};
      out.names = {"alpha", "beta", "fx", "fy", "cx", "cy"};
    } else {
      // Equidistant start: r = f theta, with f from the parabolic estimate at mid-field.
      p = {f0, f0, c.x(), c.y(), 0, 0, 0, 0};
      out.names = {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"};
    }
    for (const auto& s : samples) {
      const Vec3d ray = OmniFromMirror(s.mirror);
      if (gk == GenericKind::kKannalaBrandt)
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<GenericResidual<8>, 2, 8, 1>(new GenericResidual<8>{gk, ray, s.px}),
            nullptr, p.data(), &gamma);
      else
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<GenericResidual<6>, 2, 6, 1>(new GenericResidual<6>{gk, ray, s.px}),
            nullptr, p.data(), &gamma);
    }
    if (gk == GenericKind::kDoubleSphere) {
      problem.SetParameterLowerBound(p.data(), 0, -1.0), problem.SetParameterUpperBound(p.data(), 0, 1.0);
      problem.SetParameterLowerBound(p.data(), 1, 0.0), problem.SetParameterUpperBound(p.data(), 1, 1.0);
    } else if (gk == GenericKind::kEucm) {
      problem.SetParameterLowerBound(p.data(), 0, 0.0), problem.SetParameterUpperBound(p.data(), 0, 1.0);
      problem.SetParameterLowerBound(p.data(), 1, 1e-6);
    }
  }
  if (!o.fit_axis_rotation) problem.SetParameterBlockConstant(&gamma);
  ceres::Solver::Options so;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = so.parameter_tolerance = 1e-14;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  out.converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  out.values = p;
  out.axis_rotation_deg = gamma * 180 / M_PI;
  std::vector<double> err;
  if (o.kind == "omni") {
    UnifiedModel<double> m;
    m.width = source.width(), m.height = source.height();
    m.xi = p[0], m.fx = p[1], m.fy = p[2], m.cx = p[3], m.cy = p[4], m.distortion = {p[5], p[6], p[7], p[8]};
    for (const auto& s : samples) {
      Vec2d uv;
      if (m.ImgFromCam(AboutAxis(s.mirror, gamma), &uv))
        err.push_back((uv - s.px).norm());
      else
        ++out.outside;
    }
    out.unified = m;
  } else {
    GenericModel<double> m;
    m.kind = gk, m.width = source.width(), m.height = source.height();
    for (int k = 0; k < m.Size(); ++k) m.p[k] = p[k];
    if (gk == GenericKind::kKannalaBrandt) m.SetKannalaBrandtDomain();
    for (const auto& s : samples) {
      Vec2d uv;
      if (m.ImgFromCam(AboutAxis(OmniFromMirror(s.mirror), gamma), &uv))
        err.push_back((uv - s.px).norm());
      else
        ++out.outside;
    }
    out.generic = m;
  }
  out.px = Summarise(err);
  return out;
}

nlohmann::json RefitJson(const Refit& r) {
  nlohmann::json params;
  for (size_t k = 0; k < r.names.size(); ++k) params[r.names[k]] = r.values[k];
  return {{"model", r.kind},
          {"frame", r.kind == "omni" ? "(x, y, -z) of hovs' mirror frame (OpenCV omnidir, Kalibr omni)"
                                     : "(x, y, -z) of hovs' mirror frame: z along the optical axis"},
          {"parameters", params},
          {"converged", r.converged},
          {"axis_rotation_deg", r.axis_rotation_deg},
          {"field_deg", r.field_deg},
          {"grid_pixels", r.pixels},
          {"outside_fitted_domain", r.outside},
          {"error_px", {{"mean", r.px.mean}, {"median", r.px.median}, {"p95", r.px.p95}, {"max", r.px.max}}}};
}

}  // namespace hovs::calib
