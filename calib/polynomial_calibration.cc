#include "calib/polynomial_calibration.h"

#include <ceres/ceres.h>
#include <ceres/dynamic_autodiff_cost_function.h>
#include <ceres/rotation.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <algorithm>
#include <map>
#include <set>
#include <tuple>
#include <memory>
#include <sstream>

#include "calib/board_warp.h"
#include "calib/solver_util.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"

namespace hovs::calib {
namespace {

// Reprojection residual of one corner through the core's polynomial model. The polynomial is parametrised in
// normalised radius: f(rho) = sum_k b_k (rho / scale)^k (k = 0, 2..N), so every coefficient has a similar size.
struct ReprojectionError {
  ReprojectionError(const Vec3d& board_point, const Vec2d& pixel, int degree, double scale, double rho_hint,
                    const std::array<double, 3>* fixed_affine, const BoardExtent& board_extent)
      : P(board_point), obs(pixel), N(degree), s(scale), hint(rho_hint), affine(fixed_affine), extent(board_extent) {}

  template <class T>
  bool operator()(const T* centre, const T* aff, const T* poly, const T* aa, const T* t, const T* warp,
                  const T* decentering, T* residual) const {
    PolynomialModel<T> m;
    m.cx = centre[0], m.cy = centre[1];
    m.p1 = decentering[0], m.p2 = decentering[1];
    if (affine) {
      m.c = T((*affine)[0]), m.d = T((*affine)[1]), m.e = T((*affine)[2]);
    } else {
      m.c = aff[0], m.d = aff[1], m.e = aff[2];
    }
    m.poly.assign(N + 1, T(0));
    m.poly[0] = poly[0];
    double sk = s * s;
    for (int k = 2; k <= N; ++k, sk *= s) m.poly[k] = poly[k - 1] / T(sk);
    const Vec3<T> Pw = extent.Warped(P, warp);
    const T Pb[3] = {Pw(0), Pw(1), Pw(2)};
    T X[3];
    ceres::AngleAxisRotatePoint(aa, Pb, X);
    Vec2<T> uv;
    if (!m.ImgFromCam(Vec3<T>(X[0] + t[0], X[1] + t[1], X[2] + t[2]), &uv, hint)) return false;
    residual[0] = uv(0) - T(obs.x());
    residual[1] = uv(1) - T(obs.y());
    return true;
  }

  // For ceres::DynamicAutoDiffCostFunction: blocks centre, affine, poly (N values), angle-axis, t, board warp,
  // decentering.
  template <class T>
  bool operator()(T const* const* p, T* residual) const {
    return (*this)(p[0], p[1], p[2], p[3], p[4], p[5], p[6], residual);
  }

  Vec3d P;
  Vec2d obs;
  int N;
  double s, hint;
  const std::array<double, 3>* affine;
  BoardExtent extent;
};

// Scaramuzza's linear initialisation for one image with the centre fixed: R (first two columns) and t1, t2
// from the constraint x (r2 . P + t2) - y (r1 . P + t1) = 0, then the two sign ambiguities resolved by
// solving the polynomial (degree 2) and t3, keeping the candidate that puts every point in front.
struct LinearPose {
  Eigen::Matrix3d R;
  Vec3d t;
};

bool LinearExtrinsics(const BoardObservation& o, const Vec2d& centre, double scale, LinearPose* out) {
  const size_t n = o.pixels.size();
  Eigen::MatrixXd M(n, 6);
  for (size_t i = 0; i < n; ++i) {
    const double x = o.pixels[i].x() - centre.x(), y = o.pixels[i].y() - centre.y();
    const double X = o.board_points[i].x(), Y = o.board_points[i].y();
    M.row(i) << -y * X, -y * Y, x * X, x * Y, -y, x;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullV);
  const Eigen::VectorXd H = svd.matrixV().col(5);
  const double r11 = H(0), r12 = H(1), r21 = H(2), r22 = H(3), t1 = H(4), t2 = H(5);
  const double A = r11 * r11 + r21 * r21, B = r12 * r12 + r22 * r22, C = r11 * r12 + r21 * r22;
  const double p = 0.5 * ((B - A) + std::sqrt((B - A) * (B - A) + 4 * C * C));
  double best = HUGE_VAL;
  bool found = false;
  for (int hs : {1, -1})
    for (int rs : {1, -1}) {
      double r31 = rs * std::sqrt(std::max(p, 0.0));
      double r32 = std::abs(r31) > 1e-12 ? -C / r31 : rs * std::sqrt(std::max(p + A - B, 0.0));
      const double lambda = std::sqrt(A + r31 * r31);
      if (!(lambda > 0)) continue;
      const double k = hs / lambda;
      const Vec3d c1(r11 * k, r21 * k, r31 / lambda), c2(r12 * k, r22 * k, r32 / lambda);
      const double tt1 = t1 * k, tt2 = t2 * k;
      // Solve [a0, a2, t3] (normalised radius) from the two remaining cross-product rows.
      Eigen::MatrixXd L(2 * n, 3);
      Eigen::VectorXd b(2 * n);
      for (size_t i = 0; i < n; ++i) {
        const double x = o.pixels[i].x() - centre.x(), y = o.pixels[i].y() - centre.y();
        const double rho = std::hypot(x, y) / scale;
        const Vec3d P = o.board_points[i];
        const double bx = c1.x() * P.x() + c2.x() * P.y() + tt1, by = c1.y() * P.x() + c2.y() * P.y() + tt2;
        const double cz = c1.z() * P.x() + c2.z() * P.y();
        L.row(2 * i) << bx, bx * rho * rho, -x;
        b(2 * i) = x * cz;
        L.row(2 * i + 1) << -by, -by * rho * rho, y;
        b(2 * i + 1) = -y * cz;
      }
      const Eigen::Vector3d sol = L.colPivHouseholderQr().solve(b);
      const double err = (L * sol - b).norm();
      // Every point in front: the model's ray and the point agree in direction.
      bool front = true;
      for (size_t i = 0; i < n && front; ++i) {
        const double x = o.pixels[i].x() - centre.x(), y = o.pixels[i].y() - centre.y();
        const double rho = std::hypot(x, y) / scale;
        const Vec3d ray(x, y, sol(0) + sol(1) * rho * rho);
        const Vec3d P = o.board_points[i];
        const Vec3d Xc = c1 * P.x() + c2 * P.y() + Vec3d(tt1, tt2, sol(2));
        front = ray.dot(Xc) > 0;
      }
      // hovs' mirror frame has z towards the mirror, so the image centre looks down: a0 < 0. This picks the
      // proper configuration out of the mirror-image pair that fits equally well.
      if (!front || !(sol(0) < 0) || !(err < best)) continue;
      best = err;
      found = true;
      out->R.col(0) = c1;
      out->R.col(1) = c2;
      out->R.col(2) = c1.cross(c2).normalized();
      out->t = Vec3d(tt1, tt2, sol(2));
    }
  return found;
}

}  // namespace

void PolynomialCalibrationOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(degree >= 2 && degree <= 8, where + ".degree", "must be in 2..8 (got ", degree, ")");
  HOVS_REQUIRE(loss == "none" || loss == "huber" || loss == "cauchy", where + ".loss", "unknown loss '", loss,
               "' (known: none, huber, cauchy)");
  HOVS_REQUIRE(loss_scale > 0 && std::isfinite(loss_scale), where + ".loss_scale", "must be positive");
  HOVS_REQUIRE(max_iterations >= 1, where + ".max_iterations", "must be positive");
  HOVS_REQUIRE(outlier_sigmas == 0 || (outlier_sigmas >= 2 && std::isfinite(outlier_sigmas)), where + ".outlier_sigmas",
               "must be 0 (no rejection) or at least 2 (got ", outlier_sigmas, ")");
  HOVS_REQUIRE(outlier_floor_px >= 0 && std::isfinite(outlier_floor_px), where + ".outlier_floor_px", "must be >= 0");
}

std::vector<BoardObservation> InlierObservations(const std::vector<BoardObservation>& obs,
                                                 const PolynomialCalibration& cal) {
  if (cal.inlier.empty()) return obs;
  HOVS_REQUIRE(cal.inlier.size() == obs.size(), "calibration", "inlier table and observations differ in size");
  std::vector<BoardObservation> out;
  for (size_t i = 0; i < obs.size(); ++i) {
    BoardObservation o{obs[i].image, {}, {}};
    for (size_t j = 0; j < obs[i].pixels.size(); ++j)
      if (cal.inlier[i][j]) o.board_points.push_back(obs[i].board_points[j]), o.pixels.push_back(obs[i].pixels[j]);
    out.push_back(std::move(o));
  }
  return out;
}

PolynomialCalibration CalibratePolynomial(const std::vector<BoardObservation>& obs, int width, int height,
                                          const PolynomialCalibrationOptions& opt) {
  opt.Check("calibration");
  HOVS_REQUIRE(obs.size() >= 3, "calibration", "needs at least three images with corners (got ", obs.size(), ")");
  HOVS_REQUIRE(width > 0 && height > 0, "calibration", "image size must be positive");
  for (const auto& o : obs) {
    HOVS_REQUIRE(o.pixels.size() == o.board_points.size(), o.image, "corner and board point counts differ");
    HOVS_REQUIRE(o.pixels.size() >= 6, o.image, "needs at least 6 corners (got ", o.pixels.size(), ")");
  }
  const Vec2d centre0 = opt.initial_centre.value_or(Vec2d(0.5 * (width - 1), 0.5 * (height - 1)));
  double scale = 0;
  for (const auto& o : obs)
    for (const auto& p : o.pixels) scale = std::max(scale, (p - centre0).norm());
  HOVS_REQUIRE(scale > 1, "calibration", "the corners are all at the centre");

  // Linear initialisation: poses per image, then the polynomial and every t3 jointly.
  std::vector<LinearPose> poses(obs.size());
  for (size_t i = 0; i < obs.size(); ++i)
    HOVS_REQUIRE(LinearExtrinsics(obs[i], centre0, scale, &poses[i]), obs[i].image,
                 "degenerate board view: no pose puts every corner in front of the camera");
  const int N = opt.degree;
  size_t rows = 0;
  for (const auto& o : obs) rows += 2 * o.pixels.size();
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(rows, N + obs.size());
  Eigen::VectorXd b(rows);
  size_t r = 0;
  for (size_t i = 0; i < obs.size(); ++i) {
    const auto& R = poses[i].R;
    const auto& t = poses[i].t;
    for (size_t j = 0; j < obs[i].pixels.size(); ++j, r += 2) {
      const double x = obs[i].pixels[j].x() - centre0.x(), y = obs[i].pixels[j].y() - centre0.y();
      const double rho = std::hypot(x, y) / scale;
      const Vec3d P = obs[i].board_points[j];
      const double bx = R(0, 0) * P.x() + R(0, 1) * P.y() + t.x(), by = R(1, 0) * P.x() + R(1, 1) * P.y() + t.y();
      const double cz = R(2, 0) * P.x() + R(2, 1) * P.y();
      double pk = 1;
      for (int k = 0; k <= N; ++k, pk *= rho) {
        if (k == 1) continue;
        const int col = k == 0 ? 0 : k - 1;
        L(r, col) = bx * pk;
        L(r + 1, col) = -by * pk;
      }
      L(r, N + i) = -x;
      L(r + 1, N + i) = y;
      b(r) = x * cz;
      b(r + 1) = -y * cz;
    }
  }
  const Eigen::VectorXd lin = L.colPivHouseholderQr().solve(b);
  HOVS_REQUIRE(lin.allFinite(), "calibration", "the linear initialisation failed (degenerate board poses?)");

  // Parameter blocks.
  double centre[2] = {centre0.x(), centre0.y()};
  double affine[3] = {1, 0, 0};
  double decentering[2] = {0, 0};
  std::vector<double> poly(N);
  for (int k = 0; k < N; ++k) poly[k] = lin(k);
  std::vector<std::array<double, 6>> pose_params(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) {
    Eigen::Matrix3d R = poses[i].R;
    // Nearest rotation to the linear estimate.
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    R = svd.matrixU() * svd.matrixV().transpose();
    if (R.determinant() < 0) R.col(2) *= -1;
    pose_params[i] = PoseToParams(Rigid3d(Eigen::Quaterniond(R), Vec3d(poses[i].t.x(), poses[i].t.y(), lin(N + i))));
  }

  static const std::array<double, 3> kIdentityAffine = {1, 0, 0};
  PolynomialCalibration out;
  const BoardExtent extent = BoardExtent::Of(obs);
  // One warp shared by every image, or one per image (board_flex_per_image: a board that bends differently each
  // time it is held).
  const bool per_image = opt.board_flex && opt.board_flex_per_image;
  std::vector<std::array<double, 2>> warps(per_image ? obs.size() : 1, {0.0, 0.0});
  const auto warp_of = [&](size_t i) { return warps[per_image ? i : 0].data(); };
  const auto evaluate = [&](std::vector<double>* per_image_rms, std::vector<double>* per_image_mean, double* rms,
                            double* mean) {
    double sum2 = 0, sum = 0;
    size_t count = 0;
    for (size_t i = 0; i < obs.size(); ++i) {
      double s2 = 0, s1 = 0;
      size_t n = 0;
      for (size_t j = 0; j < obs[i].pixels.size(); ++j) {
        const double hint = (obs[i].pixels[j] - Vec2d(centre[0], centre[1])).norm();
        ReprojectionError e(obs[i].board_points[j], obs[i].pixels[j], N, scale, hint, nullptr, extent);
        double res[2] = {1e6, 1e6};
        e(centre, affine, poly.data(), pose_params[i].data(), pose_params[i].data() + 3, warp_of(i), decentering, res);
        const double d2 = res[0] * res[0] + res[1] * res[1];
        for (auto& o : out.outliers)
          if (o.image_index == static_cast<int>(i) && o.corner == static_cast<int>(j))
            o.residual_after_px = std::sqrt(d2);
        if (!out.inlier.empty() && !out.inlier[i][j]) continue;
        s2 += d2, s1 += std::sqrt(d2), ++n;
      }
      if (per_image_rms) per_image_rms->push_back(std::sqrt(s2 / n));
      if (per_image_mean) per_image_mean->push_back(s1 / n);
      sum2 += s2, sum += s1, count += n;
    }
    *rms = std::sqrt(sum2 / count);
    *mean = sum / count;
  };
  double mean0 = 0;
  evaluate(nullptr, nullptr, &out.initial_rms, &mean0);
  if (std::getenv("HOVS_CALIB_DEBUG")) {
    std::fprintf(stderr, "linear: rms %g, poly", out.initial_rms);
    for (double v : poly) std::fprintf(stderr, " %g", v);
    std::fprintf(stderr, "\n");
    for (size_t i = 0; i < obs.size(); ++i)
      std::fprintf(stderr, "  pose %zu: aa %g %g %g t %g %g %g\n", i, pose_params[i][0], pose_params[i][1],
                   pose_params[i][2], pose_params[i][3], pose_params[i][4], pose_params[i][5]);
  }

  // The joint problem over the current inlier corners (all at first).
  out.inlier.resize(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) out.inlier[i].assign(obs[i].pixels.size(), true);
  std::unique_ptr<ceres::Problem> problem;
  ceres::Solver::Options so = CalibrationSolverOptions(opt.max_iterations, 1e-14);
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  const auto solve = [&] {
    problem = std::make_unique<ceres::Problem>();
    for (size_t i = 0; i < obs.size(); ++i)
      for (size_t j = 0; j < obs[i].pixels.size(); ++j) {
        if (!out.inlier[i][j]) continue;
        const double hint = (obs[i].pixels[j] - centre0).norm();
        auto* cost = new ceres::DynamicAutoDiffCostFunction<ReprojectionError, 8>(
            new ReprojectionError(obs[i].board_points[j], obs[i].pixels[j], N, scale, hint,
                                  opt.estimate_affine ? nullptr : &kIdentityAffine, extent));
        for (int size : {2, 3, N, 3, 3, 2, 2}) cost->AddParameterBlock(size);
        cost->SetNumResiduals(2);
        problem->AddResidualBlock(
            cost, MakeLoss(opt.loss, opt.loss_scale),
            {centre, affine, poly.data(), pose_params[i].data(), pose_params[i].data() + 3, warp_of(i), decentering});
      }
    if (!opt.estimate_affine) problem->SetParameterBlockConstant(affine);
    if (!opt.estimate_decentering) problem->SetParameterBlockConstant(decentering);
    if (!opt.board_flex)
      for (auto& w : warps)
        if (problem->HasParameterBlock(w.data())) problem->SetParameterBlockConstant(w.data());
    ceres::Solve(so, problem.get(), &summary);
  };
  solve();

  // Outliers: corners whose residual exceeds outlier_sigmas robust standard deviations (sigma per axis from the
  // median residual length of the inliers: for Gaussian noise the length is Rayleigh distributed, median =
  // 1.1774 sigma), never below outlier_floor_px. Rejected corners leave the problem, which is solved again; every
  // corner is then re-tested, so a good corner that a gross error had pulled away comes back. Repeated until the
  // set is stable (at most 6 rounds). An image keeps at least 6 corners (its worst ones above the threshold stay
  // and show in its error).
  const auto residual = [&](size_t i, size_t j) {
    const double hint = (obs[i].pixels[j] - Vec2d(centre[0], centre[1])).norm();
    ReprojectionError e(obs[i].board_points[j], obs[i].pixels[j], N, scale, hint,
                        opt.estimate_affine ? nullptr : &kIdentityAffine, extent);
    double res[2] = {1e6, 1e6};
    e(centre, affine, poly.data(), pose_params[i].data(), pose_params[i].data() + 3, warp_of(i), decentering, res);
    return std::hypot(res[0], res[1]);
  };
  std::vector<std::vector<double>> first_residual(obs.size());
  for (int round = 0; opt.outlier_sigmas > 0 && round < 6; ++round) {
    std::vector<std::vector<double>> dist(obs.size());
    std::vector<double> in;
    for (size_t i = 0; i < obs.size(); ++i)
      for (size_t j = 0; j < obs[i].pixels.size(); ++j) {
        dist[i].push_back(residual(i, j));
        if (out.inlier[i][j]) in.push_back(dist[i].back());
      }
    if (round == 0) first_residual = dist;
    std::nth_element(in.begin(), in.begin() + in.size() / 2, in.end());
    const double sigma = in[in.size() / 2] / 1.1774;
    out.outlier_threshold_px = std::max(opt.outlier_floor_px, opt.outlier_sigmas * sigma);
    bool changed = false;
    for (size_t i = 0; i < obs.size(); ++i) {
      std::vector<size_t> order(obs[i].pixels.size());
      for (size_t j = 0; j < order.size(); ++j) order[j] = j;
      std::sort(order.begin(), order.end(), [&](size_t x, size_t y) { return dist[i][x] > dist[i][y]; });
      std::vector<bool> keep(order.size(), true);
      size_t kept = order.size();
      for (size_t j : order) {
        if (dist[i][j] <= out.outlier_threshold_px || kept <= 6) break;
        keep[j] = false, --kept;
      }
      changed |= keep != out.inlier[i];
      out.inlier[i] = keep;
    }
    if (!changed) break;
    solve();
  }
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t j = 0; j < obs[i].pixels.size(); ++j)
      if (!out.inlier[i][j])
        out.outliers.push_back({static_cast<int>(i), obs[i].image, static_cast<int>(j), first_residual[i][j], 0.0});
  out.converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  out.solver_report = summary.BriefReport();

  // The model.
  PolynomialModel<double>& m = out.model;
  m.width = width, m.height = height;
  m.cx = centre[0], m.cy = centre[1], m.c = affine[0], m.d = affine[1], m.e = affine[2];
  m.p1 = decentering[0], m.p2 = decentering[1];
  m.poly.assign(N + 1, 0.0);
  m.poly[0] = poly[0];
  for (int k = 2; k <= N; ++k) m.poly[k] = poly[k - 1] / std::pow(scale, k);
  double rho_min = HUGE_VAL, rho_max = 0;
  for (const auto& o : obs)
    for (const auto& p : o.pixels) {
      const double rho = m.RhoOfImg(p);
      rho_min = std::min(rho_min, rho), rho_max = std::max(rho_max, rho);
    }
  // The valid annulus: the observed radii, widened by 10 % inwards and 5 % outwards where the fitted theta(rho)
  // stays monotonic (a low-degree fit can fold just past the data).
  HOVS_REQUIRE(m.SetAnnulusWithin(rho_min, rho_max, 0.1 * rho_min, 0.05 * rho_max), "polynomial model",
               "the fitted elevation is not monotonic over the observed radii ", FormatNumber("%.1f", rho_min), "..",
               FormatNumber("%.1f", rho_max), " px: the corners do not constrain the model (try --degree 3)");
  m.FitInverse(0.01);
  for (size_t i = 0; i < obs.size(); ++i) out.cam_from_board.push_back(ParamsToPose(pose_params[i].data()));
  out.board_flex = opt.board_flex, out.board_extent = extent;
  out.board_warp = {0, 0};
  for (const auto& w : warps) out.board_warp[0] += w[0] / warps.size(), out.board_warp[1] += w[1] / warps.size();
  if (per_image) out.image_warps = warps;
  evaluate(&out.per_image_rms, &out.per_image_mean, &out.rms, &out.mean);

  // The covariance of the intrinsics and poses, and the intrinsics' standard deviations (when computable).
  // With the affine terms free, a rotation about the optical axis is a gauge freedom (poses turn, d and e
  // absorb it): the covariance is the pseudo-inverse with that one null direction removed.
  std::vector<std::pair<double*, int>> blocks = {{centre, 2}, {affine, 3}, {poly.data(), N}};
  if (opt.estimate_decentering) blocks.push_back({decentering, 2});  // intrinsics: ..., aN, p1, p2
  for (auto& p : pose_params) blocks.push_back({p.data(), 3}), blocks.push_back({p.data() + 3, 3});
  const bool shared_flex = opt.board_flex && !per_image;
  if (shared_flex) blocks.push_back({warps[0].data(), 2});
  Eigen::MatrixXd C;
  if (ParameterCovariance(problem.get(), blocks, opt.estimate_affine ? 1 : 0, &C, &out.covariance.sigma_px)) {
    Eigen::VectorXd to_model = Eigen::VectorXd::Ones(C.rows());  // a_k = b_k / scale^k
    for (int k = 2; k <= N; ++k) to_model(4 + k) = 1 / std::pow(scale, k);
    C = to_model.asDiagonal() * C * to_model.asDiagonal();
    const auto sd = [&](int i) { return std::sqrt(C(i, i)); };
    out.stddev["cx"] = sd(0), out.stddev["cy"] = sd(1);
    if (opt.estimate_affine) out.stddev["c"] = sd(2), out.stddev["d"] = sd(3), out.stddev["e"] = sd(4);
    out.stddev["a0"] = sd(5);
    for (int k = 2; k <= N; ++k) out.stddev["a" + std::to_string(k)] = sd(4 + k);
    if (opt.estimate_decentering) out.stddev["p1"] = sd(5 + N), out.stddev["p2"] = sd(6 + N);
    const int P = 5 + N + (opt.estimate_decentering ? 2 : 0) + 6 * static_cast<int>(obs.size());
    if (shared_flex) out.stddev["board_flex_x_mm"] = 1e3 * sd(P), out.stddev["board_flex_y_mm"] = 1e3 * sd(P + 1);
    out.covariance.covariance = C.topLeftCorner(P, P);
    out.covariance.cam_from_board = out.cam_from_board;
  }
  return out;
}

std::vector<BoardObservation> LoadCornerCsv(const std::filesystem::path& path) {
  return ParseCornerCsv(ReadFile(path), path.string());
}

std::vector<BoardObservation> ParseCornerCsv(const std::string& text, const std::string& source) {
  const std::filesystem::path path(source);  // names the table in errors
  std::stringstream in(NormalisedText(text));
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  HOVS_REQUIRE(line == "image,corner,board_x_mm,board_y_mm,u_px,v_px", path.string() + ":1",
               "expected the header image,corner,board_x_mm,board_y_mm,u_px,v_px");
  std::vector<BoardObservation> out;
  std::map<std::string, size_t> index;
  std::set<std::pair<std::string, long>> ids;                // (image, corner): a row given twice would count twice
  std::set<std::tuple<std::string, double, double>> points;  // (image, board x, board y)
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string where = path.string() + ":" + std::to_string(lineno);
    std::stringstream ss(line);
    std::string image, field;
    std::vector<double> v;
    std::getline(ss, image, ',');
    HOVS_REQUIRE(!image.empty(), where, "the image name is empty");
    while (std::getline(ss, field, ',')) {
      char* end = nullptr;
      const double x = std::strtod(field.c_str(), &end);
      HOVS_REQUIRE(end != field.c_str() && *end == '\0' && std::isfinite(x), where, "not a finite number: '", field,
                   "'");
      v.push_back(x);
    }
    HOVS_REQUIRE(v.size() == 5, where, "expected 6 fields (got ", v.size() + 1, ")");
    HOVS_REQUIRE(v[0] >= 0 && v[0] == std::floor(v[0]) && v[0] < 1e7, where,
                 "the corner index must be a whole number >= 0");
    for (int k = 1; k < 3; ++k)
      HOVS_REQUIRE(std::abs(v[k]) <= 1e5, where, "board coordinates must be within +-100 m (given in mm)");
    for (int k = 3; k < 5; ++k) HOVS_REQUIRE(std::abs(v[k]) <= 1e6, where, "pixel coordinates must be within +-1e6");
    HOVS_REQUIRE(ids.emplace(image, static_cast<long>(v[0])).second, where, "corner ", static_cast<long>(v[0]), " of ",
                 image, " is given twice");
    auto it = index.find(image);
    if (it == index.end()) {
      it = index.emplace(image, out.size()).first;
      out.push_back({image, {}, {}});
    }
    HOVS_REQUIRE(points.emplace(image, v[1], v[2]).second, where, "board point (", v[1], ", ", v[2], ") mm of ", image,
                 " is given twice");
    out[it->second].board_points.emplace_back(v[1] * 1e-3, v[2] * 1e-3, 0.0);
    out[it->second].pixels.emplace_back(v[3], v[4]);
  }
  HOVS_REQUIRE(!out.empty(), path.string(), "the corner table has no rows");
  return out;
}

}  // namespace hovs::calib

namespace hovs::calib {
namespace {

// Reprojection through the core's unified model. Parameters: [xi, fx, fy, cx, cy], [k1, k2, p1, p2], pose.
struct UnifiedReprojection {
  UnifiedReprojection(const Vec3d& P, const Vec2d& obs, const BoardExtent& extent)
      : P_(P), obs_(obs), extent_(extent) {}
  template <class T>
  bool operator()(const T* intr, const T* dist, const T* aa, const T* t, const T* warp, T* residual) const {
    UnifiedModel<T> m;
    m.xi = intr[0], m.fx = intr[1], m.fy = intr[2], m.cx = intr[3], m.cy = intr[4];
    m.distortion = {dist[0], dist[1], dist[2], dist[3]};
    const Vec3<T> Pw = extent_.Warped(P_, warp);
    const T Pb[3] = {Pw(0), Pw(1), Pw(2)};
    T X[3];
    ceres::AngleAxisRotatePoint(aa, Pb, X);
    Vec2<T> uv;
    if (!m.ImgFromCam(Vec3<T>(X[0] + t[0], X[1] + t[1], X[2] + t[2]), &uv)) return false;
    residual[0] = uv(0) - T(obs_.x());
    residual[1] = uv(1) - T(obs_.y());
    return true;
  }
  Vec3d P_;
  Vec2d obs_;
  BoardExtent extent_;
};

// Fits xi, fx = fy, cx, cy of a distortion-free unified model to the rays of a calibrated polynomial model.
struct RayFit {
  RayFit(const Vec3d& bearing, const Vec2d& pixel) : b_(bearing), px_(pixel) {}
  template <class T>
  bool operator()(const T* intr, T* residual) const {
    UnifiedModel<T> m;
    m.xi = intr[0], m.fx = intr[1], m.fy = intr[1], m.cx = intr[2], m.cy = intr[3];
    Vec2<T> uv;
    if (!m.ImgFromCam(Vec3<T>(T(b_.x()), T(b_.y()), T(b_.z())), &uv)) return false;
    residual[0] = uv(0) - T(px_.x());
    residual[1] = uv(1) - T(px_.y());
    return true;
  }
  Vec3d b_;
  Vec2d px_;
};

}  // namespace

UnifiedCalibration CalibrateUnified(const std::vector<BoardObservation>& obs, int width, int height,
                                    const PolynomialCalibration& start, const std::string& loss, double loss_scale,
                                    bool estimate_distortion) {
  HOVS_REQUIRE(start.cam_from_board.size() == obs.size(), "unified calibration",
               "the start has a different image count");
  const PolynomialModel<double>& poly = start.model;
  // 1. A unified model through the polynomial model's rays over the observed annulus.
  double intr4[4] = {0.9, 0, poly.cx, poly.cy};
  {
    // Focal guess from the ray at the middle of the annulus for xi = 0.9.
    const double rho = 0.5 * (poly.rho_min + poly.rho_max);
    Vec3d b;
    poly.CamFromImg(Vec2d(poly.cx + rho, poly.cy), &b);
    intr4[1] = rho * (intr4[0] * b.norm() - b.z()) / b.x();
    ceres::Problem p;
    for (int k = 0; k <= 40; ++k)
      for (int a = 0; a < 8; ++a) {
        const double r = poly.rho_min + (poly.rho_max - poly.rho_min) * k / 40.0, phi = a * M_PI / 4;
        const Vec2d uv(poly.cx + r * std::cos(phi), poly.cy + r * std::sin(phi));
        Vec3d bearing;
        if (!poly.CamFromImg(uv, &bearing)) continue;
        p.AddResidualBlock(new ceres::AutoDiffCostFunction<RayFit, 2, 4>(new RayFit(bearing, uv)), nullptr, intr4);
      }
    ceres::Solver::Options so;
    so.max_num_iterations = 100;
    ceres::Solver::Summary s;
    ceres::Solve(so, &p, &s);
  }
  // 2. The joint problem.
  double intr[5] = {intr4[0], intr4[1], intr4[1], intr4[2], intr4[3]};
  double dist[4] = {0, 0, 0, 0};
  std::vector<std::array<double, 6>> poses(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) poses[i] = PoseToParams(start.cam_from_board[i]);
  // The board's flex, when the polynomial solve estimated it, is estimated again here (same board, same extent).
  std::vector<std::array<double, 2>> warps(start.image_warps.empty() ? 1 : obs.size(), start.board_warp);
  for (size_t i = 0; i < start.image_warps.size() && i < obs.size(); ++i) warps[i] = start.image_warps[i];
  const auto warp_of = [&](size_t i) { return warps[warps.size() == 1 ? 0 : i].data(); };
  ceres::Problem problem;
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t j = 0; j < obs[i].pixels.size(); ++j) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<UnifiedReprojection, 2, 5, 4, 3, 3, 2>(
              new UnifiedReprojection(obs[i].board_points[j], obs[i].pixels[j], start.board_extent)),
          MakeLoss(loss, loss_scale), intr, dist, poses[i].data(), poses[i].data() + 3, warp_of(i));
    }
  if (!estimate_distortion) problem.SetParameterBlockConstant(dist);
  if (!start.board_flex)
    for (auto& w : warps)
      if (problem.HasParameterBlock(w.data())) problem.SetParameterBlockConstant(w.data());
  const ceres::Solver::Options so = CalibrationSolverOptions(300, 1e-14);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  UnifiedCalibration out;
  out.converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  out.solver_report = summary.BriefReport();
  auto& m = out.model;
  m.width = width, m.height = height;
  m.xi = intr[0], m.fx = intr[1], m.fy = intr[2], m.cx = intr[3], m.cy = intr[4];
  m.distortion = {dist[0], dist[1], dist[2], dist[3]};
  double sum2 = 0, sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < obs.size(); ++i) {
    out.cam_from_board.push_back(ParamsToPose(poses[i].data()));
    double s2 = 0;
    for (size_t j = 0; j < obs[i].pixels.size(); ++j) {
      Vec2d uv;
      const double d2 =
          m.ImgFromCam(out.cam_from_board[i] * start.board_extent.Warped<double>(obs[i].board_points[j], warp_of(i)),
                       &uv)
              ? (uv - obs[i].pixels[j]).squaredNorm()
              : 1e12;
      s2 += d2, sum += std::sqrt(d2);
    }
    out.per_image_rms.push_back(std::sqrt(s2 / obs[i].pixels.size()));
    sum2 += s2, count += obs[i].pixels.size();
  }
  out.rms = std::sqrt(sum2 / count);
  out.mean = sum / count;
  out.board_warp = {0, 0};
  for (const auto& w : warps) out.board_warp[0] += w[0] / warps.size(), out.board_warp[1] += w[1] / warps.size();
  if (warps.size() > 1) out.image_warps = warps;
  // The covariance of the intrinsics and poses and the intrinsics' standard deviations (no gauge freedom: the
  // skew is fixed).
  std::vector<std::pair<double*, int>> blocks = {{intr, 5}, {dist, 4}};
  for (auto& p : poses) blocks.push_back({p.data(), 3}), blocks.push_back({p.data() + 3, 3});
  Eigen::MatrixXd C;
  if (ParameterCovariance(&problem, blocks, 0, &C, &out.covariance.sigma_px)) {
    const char* names[9] = {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};
    for (int k = 0; k < 5 + 4 * estimate_distortion; ++k) out.stddev[names[k]] = std::sqrt(C(k, k));
    out.covariance.covariance = C;
    out.covariance.cam_from_board = out.cam_from_board;
  }
  return out;
}

}  // namespace hovs::calib
