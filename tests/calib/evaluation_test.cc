// calib/evaluation.h against rigs whose answer is known: a model of the rig itself, the rig with its frame turned,
// a rig with its camera moved.
#include "calib/evaluation.h"

#include <gtest/gtest.h>

#include "core/model_fit.h"
#include "tests/core/test_rigs.h"

namespace hovs::calib {
namespace {

TEST(Evaluation, AFittedPolynomialModelOfAnAlignedRigHasTinyRayErrors) {
  const auto rig = test::AlignedRig();
  const auto model = PolynomialFromCatadioptric(rig, 6);
  const RayAccuracy r = CompareWithTruth(rig, model);
  EXPECT_GT(r.pixels, 1000);
  EXPECT_LT(r.mean_deg, 2e-3);
  EXPECT_LE(r.mean_deg, r.max_deg);
  EXPECT_LE(r.mean_aligned_deg, r.mean_deg + 1e-12);
  EXPECT_LT(r.frame_rotation_deg, 0.01);
}

TEST(Evaluation, AFrameRotationIsMeasuredAndRemoved) {
  // The truth's camera turned about the mirror axis (a symmetry of the mirror): the fitted model (of the unturned
  // rig) sees every ray turned by the same rotation about z, which the aligned figure removes.
  const auto rig = test::AlignedRig();
  const auto model = PolynomialFromCatadioptric(rig, 6);
  auto turned = rig;
  const double angle = 0.2 * M_PI / 180;
  turned.cam_from_mirror =
      turned.cam_from_mirror * Rigid3d(QuaternionFromAngleAxis<double>(Vec3d(0, 0, angle)), Vec3d::Zero());
  const RayAccuracy r = CompareWithTruth(turned, model);
  EXPECT_GT(r.mean_deg, 0.1);
  EXPECT_NEAR(r.frame_rotation_deg, 0.2, 1e-3);
  EXPECT_LT(r.mean_aligned_deg, 2e-3);
}

TEST(Evaluation, AModelWhoseAnnulusMissesTheMirrorComparesNothing) {
  const auto rig = test::AlignedRig();
  auto model = PolynomialFromCatadioptric(rig, 4);
  model.rho_min = 1e6, model.rho_max = 2e6;
  const RayAccuracy r = CompareWithTruth(rig, model);
  EXPECT_EQ(r.pixels, 0);
  EXPECT_EQ(r.mean_deg, 0);
}

TEST(Evaluation, PhysicalRigErrors) {
  const auto truth = test::MisalignedRig();
  const PhysicalAccuracy same = CompareWithTruth(truth, truth);
  EXPECT_GT(same.pixels, 1000);
  EXPECT_EQ(same.max_deg, 0);
  EXPECT_EQ(same.tilt_error_deg, 0);
  EXPECT_EQ(same.centre_error_m, 0);
  // The aligned design against the misaligned truth: 1.08 deg of tilt (1, 0.4 deg); the camera centre moves by
  // the 1.5 mm offset and by the turn about F1 (0.13 m away): about 2 mm.
  const PhysicalAccuracy design = CompareWithTruth(truth, test::AlignedRig());
  EXPECT_NEAR(design.tilt_error_deg, std::hypot(1.0, 0.4), 1e-6);
  const Rigid3d eps(QuaternionFromAngleAxis<double>(Vec3d(1.0, 0.4, 0.0) * M_PI / 180), Vec3d(0.001, -0.0005, 0.001));
  const Vec3d aligned_centre = truth.mirror.SecondFocus();  // mirror frame: the aligned camera at F2
  EXPECT_NEAR(design.centre_error_m, (eps.Inverse() * aligned_centre - aligned_centre).norm(), 1e-9);
  EXPECT_GT(design.mean_deg, 0.1);
}

TEST(Evaluation, CornersAgainstTheNearestExactCorner) {
  const std::vector<Vec2d> truth = {{10, 10}, {20, 10}, {30, 10}};
  const CornerAccuracy a = CompareWithTruth({{10.3, 10.4}, {30, 10}, {19.9, 10}}, truth);
  EXPECT_NEAR(a.max_px, 0.5, 1e-12);
  EXPECT_NEAR(a.rms_px, std::sqrt((0.25 + 0 + 0.01) / 3), 1e-12);
  EXPECT_EQ(CompareWithTruth({}, truth).rms_px, 0);
}

}  // namespace
}  // namespace hovs::calib
