// The projection uncertainty predicted from one solve against the spread of the solutions over repeated draws of
// the corner noise (mrcal's validation): a camera whose models are exact for it (a unified camera, and the
// polynomial model fitted to it without noise), boards through it, and the same board poses with fresh noise.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "calib/board_suggestion.h"
#include "calib/polynomial_calibration.h"
#include "calib/projection_uncertainty.h"
#include "core/error.h"
#include "tests/calib/synthetic_boards.h"

namespace hovs::calib {
namespace {

constexpr double kNoisePx = 0.2;
constexpr int kDraws = 100;

// Worst-direction standard deviation of a set of 2-D points.
double WorstSpread(const std::vector<Vec2d>& q) {
  Vec2d mean = Vec2d::Zero();
  for (const auto& x : q) mean += x / q.size();
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
  for (const auto& x : q) c += (x - mean) * (x - mean).transpose() / (q.size() - 1);
  return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c).eigenvalues()(1));
}

std::vector<BoardObservation> WithNoise(std::vector<BoardObservation> obs, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, kNoisePx);
  for (auto& o : obs)
    for (auto& p : o.pixels) p += Vec2d(n(rng), n(rng));
  return obs;
}

// Where a solution puts the point p of the true camera frame: through every board's true and solved pose,
// averaged (the mapping the prediction linearises).
Vec3d InSolution(const std::vector<Rigid3d>& truth, const std::vector<Rigid3d>& solved, const Vec3d& p, bool infinite) {
  Vec3d out = Vec3d::Zero();
  for (size_t i = 0; i < truth.size(); ++i)
    out += infinite ? Vec3d(solved[i].rotation * (truth[i].rotation.conjugate() * p))
                    : Vec3d(solved[i] * (truth[i].Inverse() * p));
  return out / truth.size();
}

struct Case {
  std::vector<BoardObservation> clean;
  std::vector<Rigid3d> poses;
  PolynomialModel<double> poly_truth;
  UnifiedModel<double> unified_truth;
};

Case MakeCase() {
  Case c;
  UnifiedModel<double>& u = c.unified_truth;
  u.xi = 0.95, u.fx = u.fy = 150, u.cx = 321.3, u.cy = 238.6, u.width = 640, u.height = 480;
  // The polynomial truth: the polynomial model of the unified camera, from noise-free boards.
  const auto fit_obs = SyntheticBoardsThrough(u, 640, 480, 7, 11, 0.03, 16, 0.0, 5, -60, 20, 0.35, 0.9);
  PolynomialCalibrationOptions po;
  po.outlier_sigmas = 0;
  c.poly_truth = CalibratePolynomial(fit_obs, 640, 480, po).model;
  c.clean = SyntheticBoardsThrough(c.poly_truth, 640, 480, 7, 11, 0.03, 10, 0.0, 17, -60, 20, 0.35, 0.9, &c.poses);
  return c;
}

TEST(ProjectionUncertainty, PredictsTheSpreadOverNoiseDraws) {
  const Case c = MakeCase();
  ASSERT_EQ(c.clean.size(), 10u);
  PolynomialCalibrationOptions po;
  po.outlier_sigmas = 0;
  // Test pixels: three radii across the annulus, four azimuths.
  std::vector<Vec2d> pixels;
  const PolynomialModel<double>& m = c.poly_truth;
  for (double f : {0.15, 0.5, 0.85})
    for (int a = 0; a < 4; ++a) {
      const double r = m.rho_min + f * (m.rho_max - m.rho_min), phi = 0.4 + a * M_PI / 2;
      pixels.emplace_back(m.cx + r * std::cos(phi), m.cy + r * std::sin(phi));
    }
  for (const double range : {0.0, 0.5}) {
    // [model][pixel][draw]
    std::vector<std::vector<std::vector<Vec2d>>> q(2, std::vector<std::vector<Vec2d>>(pixels.size()));
    PolynomialCalibration first_poly;
    UnifiedCalibration first_unified;
    for (int k = 0; k < kDraws; ++k) {
      const auto obs = WithNoise(c.clean, 1000 + k);
      const PolynomialCalibration poly = CalibratePolynomial(obs, 640, 480, po);
      const UnifiedCalibration unified = CalibrateUnified(obs, 640, 480, poly);
      if (k == 0) first_poly = poly, first_unified = unified;
      for (size_t j = 0; j < pixels.size(); ++j) {
        Vec3d v;
        ASSERT_TRUE(c.poly_truth.CamFromImg(pixels[j], &v));
        const Vec3d p = range > 0 ? Vec3d(range * v.normalized()) : v;
        Vec2d uv;
        ASSERT_TRUE(poly.model.ImgFromCam(InSolution(c.poses, poly.cam_from_board, p, range == 0), &uv));
        q[0][j].push_back(uv);
        ASSERT_TRUE(unified.model.ImgFromCam(InSolution(c.poses, unified.cam_from_board, p, range == 0), &uv));
        q[1][j].push_back(uv);
      }
    }
    ASSERT_TRUE(first_poly.covariance.valid());
    ASSERT_TRUE(first_unified.covariance.valid());
    const ParametricModel models[2] = {ParametricModel(first_poly.model), ParametricModel(first_unified.model)};
    const SolveCovariance* cov[2] = {&first_poly.covariance, &first_unified.covariance};
    const char* names[2] = {"polynomial", "unified"};
    for (int mi = 0; mi < 2; ++mi) {
      EXPECT_NEAR(cov[mi]->sigma_px, kNoisePx, 0.02) << names[mi];
      for (size_t j = 0; j < pixels.size(); ++j) {
        const auto predicted = ProjectionUncertainty(models[mi], *cov[mi], pixels[j], range);
        ASSERT_TRUE(predicted) << names[mi] << " pixel " << pixels[j].transpose();
        const double observed = WorstSpread(q[mi][j]);
        if (std::getenv("HOVS_TEST_VERBOSE"))
          std::printf("%s range %g pixel (%.0f, %.0f): predicted %.4f px %.4f deg, observed %.4f px\n", names[mi],
                      range, pixels[j].x(), pixels[j].y(), predicted->px, predicted->deg, observed);
        EXPECT_GT(predicted->px / observed, 0.75)
            << names[mi] << " range " << range << " pixel " << pixels[j].transpose() << ": predicted " << predicted->px
            << " observed " << observed;
        EXPECT_LT(predicted->px / observed, 1.25)
            << names[mi] << " range " << range << " pixel " << pixels[j].transpose() << ": predicted " << predicted->px
            << " observed " << observed;
      }
    }
  }
}

TEST(ProjectionUncertainty, MapCoversTheFieldAndRejectsAMismatchedCovariance) {
  const Case c = MakeCase();
  PolynomialCalibrationOptions po;
  po.outlier_sigmas = 0;
  const PolynomialCalibration poly = CalibratePolynomial(WithNoise(c.clean, 7), 640, 480, po);
  ASSERT_TRUE(poly.covariance.valid());
  UncertaintyOptions uo;
  uo.centre = Vec2d(poly.model.cx, poly.model.cy);
  uo.rho_min = poly.model.rho_min, uo.rho_max = poly.model.rho_max;
  const ParametricModel model(poly.model);
  const UncertaintyMap map = ProjectionUncertaintyMap(model, poly.covariance, uo);
  if (std::getenv("HOVS_TEST_VERBOSE"))
    std::printf("map: %zu px, median %.4f p95 %.4f max %.4f px; %.4f deg\n", map.px_stats.count, map.px_stats.median,
                map.px_stats.p95, map.px_stats.max, map.deg_stats.median);
  EXPECT_GT(map.px_stats.count, 1000u);
  EXPECT_GT(map.px_stats.median, 0.0);
  EXPECT_GT(map.deg_stats.median, 0.0);
  // Every cell is the pixel's own figure; none outside the annulus.
  int checked = 0;
  for (int j = 0; j < map.ny; ++j)
    for (int i = 0; i < map.nx; ++i) {
      const Vec2d uv(i * map.step_px, j * map.step_px);
      const double r = (uv - uo.centre).norm(), v = map.px[j * map.nx + i];
      if (r < uo.rho_min || r > uo.rho_max) {
        EXPECT_TRUE(std::isnan(v));
      } else if ((i + j) % 37 == 0 && std::isfinite(v)) {
        const auto u = ProjectionUncertainty(model, poly.covariance, uv, 0);
        ASSERT_TRUE(u);
        EXPECT_DOUBLE_EQ(v, u->px);
        EXPECT_DOUBLE_EQ(map.deg[j * map.nx + i], u->deg);
        ++checked;
      }
    }
  EXPECT_GT(checked, 100);
  SolveCovariance wrong = poly.covariance;
  wrong.cam_from_board.pop_back();
  EXPECT_THROW(ProjectionUncertaintyMap(model, wrong, uo), Error);
  uo.range_m = -1;
  EXPECT_THROW(ProjectionUncertaintyMap(model, poly.covariance, uo), Error);
}

// Boards seen on one side only: adding the suggested board (rendered through the true camera with the same noise)
// lowers the uncertainty as much as predicted, and more than showing the board again where it was.
TEST(BoardSuggestion, LowersTheUncertaintyAsPredictedAndMoreThanARepeatedPose) {
  const Case c = MakeCase();
  std::vector<Rigid3d> poses;
  const auto many =
      SyntheticBoardsThrough(c.poly_truth, 640, 480, 7, 11, 0.03, 40, 0.0, 23, -60, 20, 0.35, 0.9, &poses);
  std::vector<BoardObservation> one_side;
  for (size_t i = 0; i < many.size() && one_side.size() < 8; ++i)
    if (poses[i].translation.y() > 0.1) one_side.push_back(many[i]);
  ASSERT_EQ(one_side.size(), 8u);
  PolynomialCalibrationOptions po;
  po.outlier_sigmas = 0;
  const PolynomialCalibration before = CalibratePolynomial(WithNoise(one_side, 3), 640, 480, po);
  ASSERT_TRUE(before.covariance.valid());
  UncertaintyOptions uo;
  uo.centre = Vec2d(before.model.cx, before.model.cy);
  uo.rho_min = before.model.rho_min, uo.rho_max = before.model.rho_max;
  SuggestOptions so;
  so.count = 2;
  const Suggestions s =
      SuggestBoardPoses(ParametricModel(before.model), before.covariance, one_side[0].board_points, uo, so);
  ASSERT_EQ(s.boards.size(), 2u);
  EXPECT_GT(s.candidates, 50);
  EXPECT_LT(s.boards[0].mean_px, s.mean_px_now);
  EXPECT_LE(s.boards[1].mean_px, s.boards[0].mean_px);
  // A board at `pose` through the true camera, with the same noise, then the calibration again: the field's mean.
  uo.grid_step_px = 640 / 24;
  const auto mean_with = [&](const Rigid3d& pose) {
    BoardObservation added{"added", one_side[0].board_points, {}};
    for (const auto& P : added.board_points) {
      Vec2d uv;
      EXPECT_TRUE(c.poly_truth.ImgFromCam(pose * P, &uv));
      added.pixels.push_back(uv);
    }
    std::vector<BoardObservation> with = one_side;
    with.push_back(added);
    const PolynomialCalibration after = CalibratePolynomial(WithNoise(with, 3), 640, 480, po);
    EXPECT_TRUE(after.covariance.valid());
    return ProjectionUncertaintyMap(ParametricModel(after.model), after.covariance, uo).px_stats.mean;
  };
  const double now = ProjectionUncertaintyMap(ParametricModel(before.model), before.covariance, uo).px_stats.mean;
  const double measured = mean_with(s.boards[0].cam_from_board);
  const double repeated = mean_with(before.cam_from_board[1]);
  if (std::getenv("HOVS_TEST_VERBOSE"))
    std::printf(
        "suggestion: now %.4f (map %.4f), predicted %.4f, after %.4f px, a repeated pose %.4f px; azimuth %.0f "
        "elevation %.1f\n",
        s.mean_px_now, now, s.boards[0].mean_px, measured, repeated, s.boards[0].azimuth_deg,
        s.boards[0].elevation_deg);
  EXPECT_NEAR(now, s.mean_px_now, 0.05 * now);
  EXPECT_LT(measured, 0.9 * now);
  EXPECT_NEAR(measured, s.boards[0].mean_px, 0.25 * s.boards[0].mean_px);
  EXPECT_LT(measured, repeated);
}

}  // namespace
}  // namespace hovs::calib
