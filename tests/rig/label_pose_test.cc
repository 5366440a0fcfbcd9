// The label measurement against the renderer's truth, and the visual positioning loop on the simulated unit: every
// mirror converges from the acceptance's disturbed start, and each fault ends in one error naming it.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "rig/label_pose.h"
#include "rig/positioning.h"

namespace hovs::rig {
namespace {

constexpr double kDeg = M_PI / 180;

const TurretSpec& Spec() {
  static const TurretSpec spec = LoadTurretSpec(std::string(HOVS_SOURCE_DIR) + "/scenes/turret.yaml");
  return spec;
}

TEST(Turret, PoseRoundTripsThroughCamFromMirror) {
  MirrorPose p;
  p.offset = Vec3d(1e-3, -2e-3, 3e-3);
  p.rotation = Vec3d(0.02, -0.01, 0.005);
  for (int k = 0; k < static_cast<int>(Spec().mirrors.size()); ++k) {
    const MirrorPose q = PoseFromCamFromMirror(Spec(), k, CamFromMirror(Spec(), k, p));
    EXPECT_LT((q.offset - p.offset).norm(), 1e-15);
    EXPECT_LT((q.rotation - p.rotation).norm(), 1e-15);
  }
  // Nominal axes with no seat error: the nominal pose.
  const MirrorPose n = PoseFromAxes(Spec(), 2, Spec().NominalAxes(2, 0.13), {});
  EXPECT_LT(n.offset.norm(), 1e-15);
  EXPECT_LT(n.rotation.norm(), 1e-15);
}

TEST(LabelPose, MeasuresLateralHeightAndTiltSeparately) {
  // A lateral offset alone and a tilt alone move the rim alike; the label tells them apart.
  for (int k = 0; k < static_cast<int>(Spec().mirrors.size()); ++k) {
    SCOPED_TRACE(Spec().mirrors[k].id);
    for (int c = 0; c < 2; ++c) {
      MirrorPose p;
      if (c == 0) p.offset = Vec3d(1.5e-3, -0.7e-3, 2e-3);
      if (c == 1) p.rotation = Vec3d(0.8 * kDeg, -0.5 * kDeg, 0);
      const TurretImage img = RenderTurret(Spec(), k, p, Spec().mirrors[k].PlateHeight(), 11 + c);
      const LabelMeasurement m = MeasureLabel(img, Spec(), k, {});
      EXPECT_EQ(m.markers, 4);
      EXPECT_LT(m.rms_px, 0.2);
      EXPECT_LT((m.pose.offset - p.offset).head<2>().norm(), 10e-6);
      EXPECT_LT(std::abs(m.pose.offset.z() - p.offset.z()), 10e-6);
      EXPECT_LT(std::abs(m.pose.TiltRad() - p.TiltRad()), 0.01 * kDeg);
      EXPECT_LT((m.pose.rotation - p.rotation).head<2>().norm(), 0.01 * kDeg);
    }
  }
}

TEST(LabelPose, ACoveredLabelIsAnErrorNamingIt) {
  const TurretImage img = RenderTurret(Spec(), 0, {}, 0.13, 1, /*label_covered=*/true);
  try {
    MeasureLabel(img, Spec(), 0, {});
    FAIL() << "measured a covered label";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "label");
    EXPECT_NE(std::string(e.what()).find("found 0 of 4 label markers"), std::string::npos) << e.what();
  }
}

struct LoopRun {
  AlignResult result;
  MirrorPose start;
};

LoopRun AlignFrom(int k, uint64_t seed, const std::function<void(SimulatedUnit&)>& fault = {}) {
  const TurretSpec& s = Spec();
  const auto seats = DrawSeats(s, 100 + seed);
  const auto start = DisturbedStart(s, k, seats[k], s.mirrors[k].PlateHeight(), 2e-3, 1.5 * kDeg, 3e-3, seed);
  SimulatedUnit unit(s, k, start, seats, seed);
  if (fault) fault(unit);
  LoopRun r{Align(unit, s, {}), *unit.Truth()};
  r.start = *r.result.steps.front().truth;
  return r;
}

TEST(Positioning, EveryMirrorConvergesFromTheDisturbedStart) {
  for (int k = 0; k < static_cast<int>(Spec().mirrors.size()); ++k) {
    SCOPED_TRACE(Spec().mirrors[k].id);
    const LoopRun r = AlignFrom(k, 1 + k);
    EXPECT_NEAR(r.start.LateralM(), 2e-3, 0.05e-3);
    EXPECT_NEAR(r.start.TiltRad(), 1.5 * kDeg, 0.05 * kDeg);
    EXPECT_NEAR(std::abs(r.start.offset.z()), 3e-3, 0.05e-3);
    ASSERT_TRUE(r.result.converged) << r.result.failure;
    EXPECT_LE(r.result.steps.size(), 30u);
    const MirrorPose& t = *r.result.final_truth;
    EXPECT_LT(t.LateralM(), 0.05e-3);
    EXPECT_LT(t.TiltRad(), 0.02 * kDeg);
    EXPECT_LT(std::abs(t.offset.z()), 0.05e-3);
  }
}

TEST(Positioning, AStuckAxisEndsTheLoopNamingIt) {
  const LoopRun r = AlignFrom(0, 5, [](SimulatedUnit& u) { u.sim().sim(AxisId::kY).SetFault({true, 0.0}); });
  EXPECT_FALSE(r.result.converged);
  EXPECT_EQ(r.result.failing, "y") << r.result.failure;
  EXPECT_NE(r.result.failure.find("axis y does not move"), std::string::npos) << r.result.failure;
  EXPECT_LE(r.result.steps.size(), 6u);
}

TEST(Positioning, LostStepsEndTheLoopNamingTheAxis) {
  const LoopRun r = AlignFrom(0, 6, [](SimulatedUnit& u) { u.sim().sim(AxisId::kRod).SetFault({false, 0.5}); });
  EXPECT_FALSE(r.result.converged);
  EXPECT_EQ(r.result.failing, "rod") << r.result.failure;
  EXPECT_NE(r.result.failure.find("axis rod loses steps"), std::string::npos) << r.result.failure;
  EXPECT_LE(r.result.steps.size(), 6u);
}

TEST(Positioning, ACoveredLabelEndsTheLoopNamingTheMeasurement) {
  const LoopRun r = AlignFrom(1, 7, [](SimulatedUnit& u) { u.CoverLabel(true); });
  EXPECT_FALSE(r.result.converged);
  EXPECT_EQ(r.result.failing, "label");
  EXPECT_NE(r.result.failure.find("could not be measured in 3 images"), std::string::npos) << r.result.failure;
  EXPECT_EQ(r.result.steps.size(), 3u);
}

}  // namespace
}  // namespace hovs::rig
