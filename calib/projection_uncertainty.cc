#include "calib/projection_uncertainty.h"

#include <ceres/jet.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>

#include "calib/solver_util.h"
#include "core/error.h"
#include "core/format.h"

namespace hovs::calib {
namespace {

constexpr int kMaxIntrinsics = 16;
using IntrinsicsJet = ceres::Jet<double, kMaxIntrinsics>;
using PointJet = ceres::Jet<double, 3>;

template <class T>
PolynomialModel<T> PolynomialOf(const PolynomialModel<double>& m, const T* v) {
  PolynomialModel<T> out;
  out.width = m.width, out.height = m.height;
  out.cx = v[0], out.cy = v[1], out.c = v[2], out.d = v[3], out.e = v[4];
  out.poly.assign(m.poly.size(), T(0));
  out.poly[0] = v[5];
  for (size_t k = 2; k < m.poly.size(); ++k) out.poly[k] = v[4 + k];
  if (m.HasDecentering()) out.p1 = v[3 + m.poly.size()], out.p2 = v[4 + m.poly.size()];
  out.inv_cheb = m.inv_cheb, out.inv_poly = m.inv_poly;
  out.inv_theta_lo = m.inv_theta_lo, out.inv_theta_hi = m.inv_theta_hi;
  out.rho_min = m.rho_min, out.rho_max = m.rho_max;
  return out;
}

template <class T>
UnifiedModel<T> UnifiedOf(const UnifiedModel<double>& m, const T* v) {
  UnifiedModel<T> out;
  out.width = m.width, out.height = m.height;
  out.xi = v[0], out.fx = v[1], out.fy = v[2], out.cx = v[3], out.cy = v[4], out.skew = T(m.skew);
  out.distortion = {v[5], v[6], v[7], v[8]};
  return out;
}

// Projects p (scalar type T) with intrinsics v (type T) through the model `m`; the polynomial's Newton starts at
// the nominal radius `hint`.
template <class T>
bool Project(const std::variant<PolynomialModel<double>, UnifiedModel<double>>& m, const T* v, const Vec3<T>& p,
             double hint, Vec2<T>* uv) {
  if (const auto* poly = std::get_if<PolynomialModel<double>>(&m))
    return PolynomialOf(*poly, v).ImgFromCam(p, uv, hint);
  return UnifiedOf(std::get<UnifiedModel<double>>(m), v).ImgFromCam(p, uv);
}

// Worst-direction standard deviation of a 2 x 2 covariance.
double WorstSigma(const Eigen::Matrix2d& c) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c);
  return std::sqrt(std::max(0.0, es.eigenvalues()(1)));
}

}  // namespace

ParametricModel::ParametricModel(const PolynomialModel<double>& m) : model_(m) {
  values_ = {m.cx, m.cy, m.c, m.d, m.e, m.poly.at(0)};
  for (size_t k = 2; k < m.poly.size(); ++k) values_.push_back(m.poly[k]);
  if (m.HasDecentering()) values_.push_back(m.p1), values_.push_back(m.p2);  // estimated: part of the covariance
  HOVS_REQUIRE(size() <= kMaxIntrinsics, "projection uncertainty", "polynomial degree ", m.Degree(), " is too high");
}

ParametricModel::ParametricModel(const UnifiedModel<double>& m) : model_(m) {
  values_ = {m.xi, m.fx, m.fy, m.cx, m.cy, m.distortion.k1, m.distortion.k2, m.distortion.p1, m.distortion.p2};
}

int ParametricModel::width() const {
  return std::visit([](const auto& m) { return m.width; }, model_);
}
int ParametricModel::height() const {
  return std::visit([](const auto& m) { return m.height; }, model_);
}

bool ParametricModel::CamFromImg(const Vec2d& uv, Vec3d* ray) const {
  return std::visit([&](const auto& m) { return m.CamFromImg(uv, ray); }, model_);
}

bool ParametricModel::ImgFromCam(const Vec3d& p, Vec2d* uv) const {
  return std::visit([&](const auto& m) { return m.ImgFromCam(p, uv); }, model_);
}

bool ParametricModel::ImgFromCamJacobians(const Vec3d& p, Vec2d* uv, Eigen::MatrixXd* d_intr,
                                          Eigen::Matrix<double, 2, 3>* d_point) const {
  if (!ImgFromCam(p, uv)) return false;
  double hint = -1;
  if (const auto* poly = std::get_if<PolynomialModel<double>>(&model_)) hint = poly->RhoOfImg(*uv);
  const int K = size();
  std::vector<IntrinsicsJet> vj(K);
  for (int k = 0; k < K; ++k) vj[k] = IntrinsicsJet(values_[k], k);
  Vec2<IntrinsicsJet> qj;
  if (!Project(model_, vj.data(), Vec3<IntrinsicsJet>(IntrinsicsJet(p.x()), IntrinsicsJet(p.y()), IntrinsicsJet(p.z())),
               hint, &qj))
    return false;
  d_intr->resize(2, K);
  for (int r = 0; r < 2; ++r) d_intr->row(r) = qj(r).v.head(K).transpose();
  std::vector<PointJet> vp(K);
  for (int k = 0; k < K; ++k) vp[k] = PointJet(values_[k]);
  Vec2<PointJet> qp;
  if (!Project(model_, vp.data(), Vec3<PointJet>(PointJet(p.x(), 0), PointJet(p.y(), 1), PointJet(p.z(), 2)), hint,
               &qp))
    return false;
  for (int r = 0; r < 2; ++r) d_point->row(r) = qp(r).v.transpose();
  return std::isfinite(d_intr->sum()) && d_point->allFinite();
}

Eigen::Matrix3d RotatedPointJacobian(const double* params, const Vec3d& b) {
  PointJet aa[3], bj[3] = {PointJet(b.x()), PointJet(b.y()), PointJet(b.z())}, out[3];
  for (int k = 0; k < 3; ++k) aa[k] = PointJet(params[k], k);
  ceres::AngleAxisRotatePoint(aa, bj, out);
  Eigen::Matrix3d d;
  for (int r = 0; r < 3; ++r) d.row(r) = out[r].v.transpose();
  return d;
}

bool ProjectionGradient(const ParametricModel& model, const std::vector<Rigid3d>& cam_from_board, const Vec3d& p,
                        bool infinite, Eigen::MatrixXd* G, Eigen::Matrix<double, 2, 3>* d_point) {
  Vec2d uv;
  Eigen::MatrixXd d_intr;
  if (!model.ImgFromCamJacobians(p, &uv, &d_intr, d_point)) return false;
  const int K = model.size(), n = static_cast<int>(cam_from_board.size());
  G->setZero(2, K + 6 * n);
  G->leftCols(K) = d_intr;
  for (int i = 0; i < n; ++i) {
    const Rigid3d& T = cam_from_board[i];
    const std::array<double, 6> params = PoseToParams(T);
    // The point in board i's frame; the perturbed pose maps it back: R(aa') b + t'.
    const Vec3d b = infinite ? Vec3d(T.rotation.conjugate() * p) : Vec3d(T.Inverse() * p);
    G->block(0, K + 6 * i, 2, 3) = *d_point * RotatedPointJacobian(params.data(), b) / n;
    if (!infinite) G->block(0, K + 6 * i + 3, 2, 3) = *d_point / n;
  }
  return true;
}

std::optional<PixelUncertainty> ProjectionUncertainty(const ParametricModel& model, const SolveCovariance& solve,
                                                      const Vec2d& uv, double range_m) {
  Vec3d v;
  if (!model.CamFromImg(uv, &v)) return std::nullopt;
  v.normalize();
  PixelUncertainty out;
  Eigen::MatrixXd G;
  Eigen::Matrix<double, 2, 3> d_point;
  // At infinity: the pixel covariance, and through the projection's Jacobian on the tangent plane of the ray, the
  // ray's angular covariance.
  if (!ProjectionGradient(model, solve.cam_from_board, v, true, &G, &d_point)) return std::nullopt;
  const Eigen::Matrix2d c_inf = G * solve.covariance * G.transpose();
  Eigen::Matrix<double, 3, 2> tangent;
  tangent.col(0) = v.unitOrthogonal();
  tangent.col(1) = v.cross(tangent.col(0));
  const Eigen::Matrix2d A = d_point * tangent;  // px per radian
  if (!(std::abs(A.determinant()) > 0)) return std::nullopt;
  const Eigen::Matrix2d Ai = A.inverse();
  out.ray_covariance = Ai * c_inf * Ai.transpose();
  out.deg = WorstSigma(out.ray_covariance) * 180 / M_PI;
  if (range_m > 0) {
    if (!ProjectionGradient(model, solve.cam_from_board, range_m * v, false, &G, &d_point)) return std::nullopt;
    out.covariance = G * solve.covariance * G.transpose();
  } else {
    out.covariance = c_inf;
  }
  out.px = WorstSigma(out.covariance);
  return out;
}

void UncertaintyOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(range_m >= 0 && std::isfinite(range_m), where, "the range must be >= 0 m (0: infinity)");
  HOVS_REQUIRE(grid_step_px >= 0 && grid_step_px <= 10000, where, "the grid step must be 0 (automatic) to 10000 px");
  HOVS_REQUIRE(rho_min >= 0 && rho_max >= 0 && std::isfinite(rho_min) && std::isfinite(rho_max), where,
               "the annulus radii must be >= 0");
}

UncertaintyMap ProjectionUncertaintyMap(const ParametricModel& model, const SolveCovariance& solve,
                                        const UncertaintyOptions& o) {
  o.Check("projection uncertainty");
  HOVS_REQUIRE(solve.valid(), "projection uncertainty", "the solve's covariance is not available");
  const int expected = model.size() + 6 * static_cast<int>(solve.cam_from_board.size());
  HOVS_REQUIRE(solve.covariance.rows() == expected && solve.covariance.cols() == expected, "projection uncertainty",
               "the covariance is ", solve.covariance.rows(), "x", solve.covariance.cols(), ", expected ", expected,
               "x", expected);
  UncertaintyMap map;
  static_cast<ImageGrid&>(map) = ImageGrid::Over(model.width(), model.height(), o.grid_step_px);
  map.range_m = o.range_m, map.sigma_px = solve.sigma_px;
  map.px.assign(map.nx * map.ny, NAN), map.deg.assign(map.nx * map.ny, NAN);
  std::vector<double> px, deg;
  for (int j = 0; j < map.ny; ++j)
    for (int i = 0; i < map.nx; ++i) {
      const Vec2d uv(i * map.step_px, j * map.step_px);
      const double r = (uv - o.centre).norm();
      if (o.rho_max > 0 && (r < o.rho_min || r > o.rho_max)) continue;
      const auto u = ProjectionUncertainty(model, solve, uv, o.range_m);
      if (!u) continue;
      map.px[j * map.nx + i] = u->px, map.deg[j * map.nx + i] = u->deg;
      px.push_back(u->px), deg.push_back(u->deg);
    }
  map.px_stats = Summarise(px), map.deg_stats = Summarise(deg);
  return map;
}

nlohmann::json UncertaintyJson(const UncertaintyMap& m) {
  const auto stats = [](const SampleSummary& s) {
    return nlohmann::json{{"mean", s.mean}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
  };
  return {{"method", "projection of a fixed point through the solve's covariance (mrcal's mean of the boards' frames)"},
          {"range_m", m.range_m > 0 ? nlohmann::json(m.range_m) : nlohmann::json("infinity")},
          {"sigma_px", m.sigma_px},
          {"grid_step_px", m.step_px},
          {"pixels", m.px_stats.count},
          {"px", stats(m.px_stats)},
          {"deg", stats(m.deg_stats)}};
}

void WriteUncertaintyFigures(const UncertaintyMap& m, const std::string& title, const std::filesystem::path& px_png,
                             const std::filesystem::path& deg_png) {
  const std::string note = "outside the calibrated field";
  const std::string range = m.range_m > 0 ? FormatNumber("%.3g", m.range_m) + " m" : std::string("infinity");
  WriteGridMap(m, m.px, title + ", 1-sigma px at " + range, m.px_stats, "%.3f", note, px_png);
  WriteGridMap(m, m.deg, title + ", 1-sigma ray, degrees", m.deg_stats, "%.4f", note, deg_png);
}

}  // namespace hovs::calib
