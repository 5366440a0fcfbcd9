#include "calib/rim_positioning.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <cmath>

#include "core/error.h"

namespace hovs::calib {
namespace {

// Circle through points (algebraic least squares): centre and radius.
void FitCircle(const std::vector<Vec2d>& p, Vec2d* centre, double* radius) {
  Eigen::MatrixXd A(p.size(), 3);
  Eigen::VectorXd b(p.size());
  for (size_t i = 0; i < p.size(); ++i) {
    A.row(i) << p[i].x(), p[i].y(), 1.0;
    b(i) = -p[i].squaredNorm();
  }
  const Eigen::Vector3d s = A.colPivHouseholderQr().solve(b);
  *centre = Vec2d(-s(0) / 2, -s(1) / 2);
  *radius = std::sqrt(std::max(0.0, centre->squaredNorm() - s(2)));
}

// The nominal rim image: projections of the rim circle.
std::vector<Vec2d> NominalRim(const CatadioptricCamera<double>& rig, int n) {
  std::vector<Vec2d> out;
  const double R = rig.mirror.RimRadius(), z = rig.mirror.RimZ();
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    Vec2d uv;
    if (rig.camera.ImgFromCam(rig.cam_from_mirror * Vec3d(R * std::cos(a), R * std::sin(a), z), &uv)) out.push_back(uv);
  }
  return out;
}

double Sample(const uint8_t* g, int w, int h, double x, double y) {
  if (!(x >= 0 && y >= 0 && x <= w - 1.001 && y <= h - 1.001)) return NAN;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const uint8_t* p = g + static_cast<size_t>(y0) * w + x0;
  return (1 - fy) * ((1 - fx) * p[0] + fx * p[1]) + fy * ((1 - fx) * p[w] + fx * p[w + 1]);
}

struct RimResidual {
  Vec3d ray;  // camera frame, unit
  Rigid3d mirror_from_cam_nominal;
  double R, z, f;
  template <class T>
  bool operator()(const T* offset, T* r) const {
    // Orientation nominal; centre = nominal centre + offset.
    const Vec3<T> C = mirror_from_cam_nominal.translation.cast<T>() + Vec3<T>(offset[0], offset[1], offset[2]);
    const Vec3<T> d = (mirror_from_cam_nominal.rotation * ray).cast<T>();
    if (!(ScalarPart(d(2)) > 1e-9)) return false;
    const T t = (T(z) - C(2)) / d(2);
    const Vec3<T> X = C + t * d;
    using std::sqrt;
    r[0] = (sqrt(X(0) * X(0) + X(1) * X(1)) - T(R)) * T(f) / (T(z) - C(2));
    return true;
  }
};

}  // namespace

void RimEdgeOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(rays >= 16 && rays <= 100000, where, "rays must be in 16..100000 (got ", rays, ")");
  HOVS_REQUIRE(std::isfinite(search_px) && search_px > 1 && search_px <= 2000, where,
               "search_px (the search half width) must be in (1, 2000] px (got ", search_px, ")");
  HOVS_REQUIRE(std::isfinite(min_step) && min_step > 0 && min_step <= 255, where,
               "min_step (the edge's grey step) must be in (0, 255] (got ", min_step, ")");
}

RimEdge DetectRimEdge(const uint8_t* grey, int width, int height, const CatadioptricCamera<double>& rig,
                      const RimEdgeOptions& o) {
  o.Check("rim detection");
  HOVS_REQUIRE(width == rig.camera.width && height == rig.camera.height, "rim detection", "the image is ", width, "x",
               height, " but the nominal camera is ", rig.camera.width, "x", rig.camera.height);
  Vec2d c0;
  double r0 = 0;
  FitCircle(NominalRim(rig, 360), &c0, &r0);
  RimEdge out;
  out.rays = o.rays;
  const double step = 0.5;
  const int n = static_cast<int>(2 * o.search_px / step) + 1;
  std::vector<double> prof(n), grad(n);
  for (int k = 0; k < o.rays; ++k) {
    const double a = 2 * M_PI * k / o.rays;
    const Vec2d dir(std::cos(a), std::sin(a));
    bool ok = true;
    for (int i = 0; i < n && ok; ++i) {
      const Vec2d p = c0 + (r0 - o.search_px + i * step) * dir;
      prof[i] = Sample(grey, width, height, p.x(), p.y());
      ok = std::isfinite(prof[i]);
    }
    if (!ok) continue;
    int best = -1;
    double bg = 0;
    for (int i = 1; i + 1 < n; ++i) {
      grad[i] = std::abs(prof[i + 1] - prof[i - 1]) / (2 * step);
      if (grad[i] > bg) bg = grad[i], best = i;
    }
    if (best < 2 || best > n - 3) continue;
    // The step across the edge: the profile a few pixels either side.
    const int span = static_cast<int>(3 / step);
    const double across = std::abs(prof[std::min(n - 1, best + span)] - prof[std::max(0, best - span)]);
    if (across < o.min_step) continue;
    const double gm = grad[best - 1], gp = grad[best + 1], den = gm - 2 * bg + gp;
    const double sub = den < 0 ? 0.5 * (gm - gp) / den : 0.0;
    out.points.push_back(c0 + (r0 - o.search_px + (best + sub) * step) * dir);
  }
  return out;
}

bool ReflectionMeetsMount(const CatadioptricCamera<double>& rig, const Vec2d& pixel) {
  Vec3d ray;
  if (!rig.camera.CamFromImg(pixel, &ray)) return false;
  const Rigid3d mirror_from_cam = rig.cam_from_mirror.Inverse();
  const Vec3d c = mirror_from_cam.translation, v = mirror_from_cam.rotation * ray;
  const double z = rig.mirror.RimZ();
  if (!(std::abs(v.z()) > 1e-12)) return false;
  // The rim point in the pixel's direction: the ray meets the rim plane; scaled onto the rim circle.
  const Vec3d hit = c + v * ((z - c.z()) / v.z());
  const double r = hit.head<2>().norm();
  if (!(r > 0)) return false;
  const Vec3d m(hit.x() * rig.mirror.RimRadius() / r, hit.y() * rig.mirror.RimRadius() / r, z);
  const Vec3d in = (m - c).normalized(), n = rig.mirror.Normal(m);
  const Vec3d out = in - 2 * in.dot(n) * n;
  return out.z() > std::sin(-kRimClearanceDeg * M_PI / 180);
}

MirrorPosition EstimateMirrorPosition(const RimEdge& edge, const CatadioptricCamera<double>& rig) {
  HOVS_REQUIRE(edge.points.size() >= 20, "mirror positioning", "only ", edge.points.size(),
               " rim edge points (at least 20 needed): is the rim in the image?");
  const Rigid3d mirror_from_cam = rig.cam_from_mirror.Inverse();
  const double R = rig.mirror.RimRadius(), z = rig.mirror.RimZ(), f = 0.5 * (rig.camera.fx + rig.camera.fy);
  double offset[3] = {0, 0, 0};
  ceres::Problem problem;
  for (const Vec2d& p : edge.points) {
    Vec3d ray;
    if (!rig.camera.CamFromImg(p, &ray)) continue;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<RimResidual, 1, 3>(new RimResidual{ray, mirror_from_cam, R, z, f}),
        new ceres::HuberLoss(1.0), offset);
  }
  ceres::Solver::Options so;
  so.max_num_iterations = 100;
  so.function_tolerance = so.parameter_tolerance = so.gradient_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  MirrorPosition out;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.offset = Vec3d(offset[0], offset[1], offset[2]);
  out.points = static_cast<int>(problem.NumResidualBlocks());
  out.rms_px = std::sqrt(2 * summary.final_cost / std::max(1, out.points));
  for (const Vec2d& p : edge.points) {
    Vec3d ray;
    double r = 0;
    if (rig.camera.CamFromImg(p, &ray) && RimResidual{ray, mirror_from_cam, R, z, f}(offset, &r) &&
        std::abs(r) <= kRimInlierPx)
      ++out.inliers;
  }
  out.inlier_fraction = edge.points.empty() ? 0.0 : double(out.inliers) / edge.points.size();
  const double dz = z - (mirror_from_cam.translation.z() + offset[2]);
  out.equivalent_tilt_rad = Vec2d(std::atan2(offset[0], dz), std::atan2(offset[1], dz));
  FitCircle(edge.points, &out.rim_centre_px, &out.rim_radius_px);
  FitCircle(NominalRim(rig, 360), &out.nominal_rim_centre_px, &out.nominal_rim_radius_px);
  return out;
}

CatadioptricCamera<double> WithCameraOffset(const CatadioptricCamera<double>& nominal, const Vec3d& offset) {
  CatadioptricCamera<double> r = nominal;
  Rigid3d mirror_from_cam = nominal.cam_from_mirror.Inverse();
  mirror_from_cam.translation += offset;
  r.cam_from_mirror = mirror_from_cam.Inverse();
  return r;
}

MirrorPosition LocateMirror(const uint8_t* grey, int width, int height, const CatadioptricCamera<double>& nominal,
                            const RimEdgeOptions& o, RimEdge* edge, const std::string& where) {
  const auto estimate = [&](const RimEdge& e) {
    HOVS_REQUIRE(e.points.size() >= 20, where, "no rim: only ", e.points.size(), " of ", e.rays,
                 " rays show an edge near the design's rim (at least 20 needed): is the rim in the image?");
    return EstimateMirrorPosition(e, nominal);
  };
  const MirrorPosition first = estimate(DetectRimEdge(grey, width, height, nominal, o));
  RimEdgeOptions fine = o;
  fine.search_px = std::max(3.0, o.search_px / 4);
  const RimEdge second = DetectRimEdge(grey, width, height, WithCameraOffset(nominal, first.offset), fine);
  if (edge) *edge = second;
  MirrorPosition p = estimate(second);
  // Where the reflection at the rim leaves upwards (the field's top above the rim plane there: a camera off its
  // focus, closer or to the side), the rays reflected next to the rim meet the mount ring's underside, the last
  // pixels inside the rim image are dark and the visible edge lies up to a few pixels inside the rim. Those edge
  // points are dropped and the position estimated again (twice: the first drop moves the estimate).
  for (int pass = 0; pass < 2; ++pass) {
    const CatadioptricCamera<double> rig = WithCameraOffset(nominal, p.offset);
    RimEdge clear = second;
    clear.points.clear();
    for (const Vec2d& q : second.points)
      if (!ReflectionMeetsMount(rig, q)) clear.points.push_back(q);
    if (clear.points.size() == second.points.size() || clear.points.size() < 20) break;
    const int occluded = static_cast<int>(second.points.size() - clear.points.size());
    p = EstimateMirrorPosition(clear, nominal);
    p.occluded = occluded;
  }
  HOVS_REQUIRE(p.inlier_fraction >= kRimMinInlierFraction && p.inliers >= kRimMinRayFraction * second.rays, where,
               "no rim: of ", second.rays, " rays, ", p.inliers, " show an edge within ", kRimInlierPx,
               " px of one rim (", static_cast<int>(std::lround(100 * p.inlier_fraction)),
               " % of the edges found); a rim needs ", static_cast<int>(100 * kRimMinInlierFraction), " % and ",
               static_cast<int>(std::ceil(kRimMinRayFraction * second.rays)), " rays");
  return p;
}

}  // namespace hovs::calib
