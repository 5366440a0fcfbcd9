// Model differences, held-out board poses and cross-validation, against known answers.
#include <gtest/gtest.h>

#include <cmath>

#include "calib/board_pose.h"
#include "calib/cross_validation.h"
#include "calib/model_diff.h"
#include "core/error.h"
#include "core/model_fit.h"
#include "tests/calib/synthetic_boards.h"
#include "tests/core/test_rigs.h"

namespace hovs::calib {
namespace {

// The same rig with its mirror frame turned 0.5 degrees about the axis (the mirror is symmetric, so the camera is
// physically the same): the diff finds the rotation and nothing else; without the rotation it shows pixels.
TEST(ModelDiff, FindsTheFrameRotationAndNothingElse) {
  const auto rig = test::AlignedRig();
  auto turned = rig;
  turned.cam_from_mirror =
      turned.cam_from_mirror *
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI / 180, Vec3d::UnitZ())), Vec3d::Zero());
  const AnyModel a = AnyModel::Exact(rig), b = AnyModel::Exact(turned);
  const ModelDiff same = DiffModels(a, a);
  EXPECT_LT(same.px_stats.max, 1e-9);
  EXPECT_GT(same.common_pixels, 2000u);
  const ModelDiff d = DiffModels(a, b);
  EXPECT_NEAR(d.rotation_deg, 0.5, 1e-3);
  EXPECT_LT(d.px_stats.max, 1e-3);
  EXPECT_LT(d.deg_stats.max, 1e-5);
  ModelDiffOptions fixed;
  fixed.fit_rotation = false;
  const ModelDiff raw = DiffModels(a, b, fixed);
  EXPECT_GT(raw.px_stats.median, 1.0);  // 0.5 deg about the axis moves the image's pixels by 1-10 px
  EXPECT_NEAR(raw.deg_stats.max, 0.5, 0.01);
  // A polynomial fit of the rig differs from it by its fit error only.
  const ModelDiff fit = DiffModels(a, AnyModel::Polynomial(PolynomialFromCatadioptric(rig, 5)));
  EXPECT_LT(fit.px_stats.p95, 0.02);
  EXPECT_LT(fit.rotation_deg, 1e-3);
  // The RMS of identical diffs is the diff; sizes that differ are refused.
  EXPECT_NEAR(RmsOfDiffs({raw, raw}).px_stats.median, raw.px_stats.median, 1e-12);
  auto small = test::AlignedRig();
  small.camera = PinholeCamera<double>::FromPhysical(0.016, 2 * 4.54e-6, 1375, 1100);
  EXPECT_THROW(DiffModels(a, AnyModel::Exact(small)), Error);
}

TEST(BoardPose, RecoversTheBoardPoseThroughAFixedModel) {
  const auto rig = test::AlignedRig();
  std::vector<Rigid3d> poses;
  const auto obs = SyntheticObservations(rig, 5, 0.0, 21, &poses);
  for (size_t i = 0; i < obs.size(); ++i) {
    Rigid3d pose;
    double rms = 0;
    ASSERT_TRUE(FitBoardPose(AnyModel::Exact(rig), obs[i].board_points, obs[i].pixels, &pose, &rms));
    EXPECT_LT(rms, 1e-4);
    EXPECT_LT((pose.translation - poses[i].translation).norm(), 1e-6);
    EXPECT_LT(pose.rotation.angularDistance(poses[i].rotation), 1e-6);
  }
}

// 12 images with 0.1 px noise, 3 folds: the held-out error is the noise's (a little above the fit's); the folds'
// models differ from the full one in proportion to the noise (the same boards with 0.02 px: five times less).
TEST(CrossValidation, HeldOutErrorAndSpreadOfNoisyCorners) {
  const auto rig = test::AlignedRig();
  const auto obs = SyntheticObservations(rig, 12, 0.1, 5);
  const PolynomialCalibration full = CalibratePolynomial(obs, 2750, 2200, {});
  const CrossValidation cv = CrossValidatePolynomial(obs, 2750, 2200, {}, 3, full.model);
  ASSERT_EQ(cv.fold.size(), 3u);
  EXPECT_EQ(cv.fold[0].held_out.size(), 4u);
  EXPECT_GT(cv.held_out_rms, cv.train_rms);
  EXPECT_GT(cv.held_out_rms, 0.1);
  EXPECT_LT(cv.held_out_rms, 0.2);
  std::printf("[ figure ] held-out %.4f px, fit %.4f px, spread median %.4f px (%.5f deg), 95 %% %.4f px\n",
              cv.held_out_rms, cv.train_rms, cv.spread.px_stats.median, cv.spread.deg_stats.median,
              cv.spread.px_stats.p95);
  const auto quiet = SyntheticObservations(rig, 12, 0.02, 5);
  const CrossValidation cv_quiet =
      CrossValidatePolynomial(quiet, 2750, 2200, {}, 3, CalibratePolynomial(quiet, 2750, 2200, {}).model);
  const double ratio = cv.spread.px_stats.median / cv_quiet.spread.px_stats.median;
  EXPECT_GT(ratio, 3.5);
  EXPECT_LT(ratio, 6.5);
  EXPECT_THROW(CrossValidatePolynomial(obs, 2750, 2200, {}, 1, full.model), Error);
  EXPECT_THROW(CrossValidatePolynomial(std::vector<BoardObservation>(obs.begin(), obs.begin() + 4), 2750, 2200, {}, 2,
                                       full.model),
               Error);
}

}  // namespace
}  // namespace hovs::calib

namespace hovs::calib {
namespace {

// Corners of a board bulging 0.3 mm along x and -0.2 mm along y (calib/board_warp.h), through the exact rig with
// 0.05 px noise: the flat-board solve is left with the bulge in its residuals; with --board-flex the bulge is
// found again (within 0.03 mm) and the fit is at the noise floor, for both models.
TEST(BoardFlex, RecoversTheBulgeOfABentBoard) {
  const auto rig = test::AlignedRig();
  std::vector<Rigid3d> poses;
  auto obs = SyntheticObservations(rig, 12, 0.0, 9, &poses);
  const BoardExtent extent = BoardExtent::Of(obs);
  const std::array<double, 2> bulge = {0.3e-3, -0.2e-3};
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0, 0.05);
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t k = 0; k < obs[i].pixels.size(); ++k) {
      Vec2d uv;
      ASSERT_EQ(rig.ImgFromMirror(poses[i] * extent.Warped<double>(obs[i].board_points[k], bulge.data()), &uv),
                ProjectionStatus::kOk);
      obs[i].pixels[k] = uv + Vec2d(noise(rng), noise(rng));
    }
  const PolynomialCalibration flat = CalibratePolynomial(obs, 2750, 2200, {});
  PolynomialCalibrationOptions o;
  o.board_flex = true;
  const PolynomialCalibration bent = CalibratePolynomial(obs, 2750, 2200, o);
  EXPECT_GT(flat.rms, bent.rms + 0.01);
  EXPECT_LT(bent.rms, 0.075);  // the noise floor: 0.05 sqrt(2) = 0.071 px
  EXPECT_NEAR(bent.board_warp[0], bulge[0], 0.03e-3);
  EXPECT_NEAR(bent.board_warp[1], bulge[1], 0.03e-3);
  EXPECT_GT(bent.stddev.count("board_flex_x_mm"), 0u);
  const UnifiedCalibration unified = CalibrateUnified(obs, 2750, 2200, bent);
  EXPECT_LT(unified.rms, 0.075);
  EXPECT_NEAR(unified.board_warp[0], bulge[0], 0.03e-3);
  // One warp per image: each image finds the same bulge again, less precisely (35 corners each: about 0.1 mm).
  o.board_flex_per_image = true;
  const PolynomialCalibration each = CalibratePolynomial(obs, 2750, 2200, o);
  ASSERT_EQ(each.image_warps.size(), obs.size());
  double ss = 0;
  for (const auto& w : each.image_warps) ss += std::pow(w[0] - bulge[0], 2) + std::pow(w[1] - bulge[1], 2);
  EXPECT_LT(std::sqrt(ss / (2 * obs.size())), 0.15e-3);
  EXPECT_NEAR(each.board_warp[0], bulge[0], 0.05e-3);
  EXPECT_LE(each.rms, bent.rms);
  std::printf("[ figure ] bent board: flat solve %.4f px, with flex %.4f px, bulge found (%.4f, %.4f) mm\n", flat.rms,
              bent.rms, 1e3 * bent.board_warp[0], 1e3 * bent.board_warp[1]);
}

}  // namespace
}  // namespace hovs::calib
