// The focus loop against a dense sweep of the same sharpness measure, and the flat-sharpness error.
#include <gtest/gtest.h>

#include "core/error.h"
#include "rig/focus.h"

namespace hovs::rig {
namespace {

TurretSpec QuickSpec() {
  TurretSpec s = LoadTurretSpec(std::string(HOVS_SOURCE_DIR) + "/scenes/turret.yaml");
  s.downscale = 2;  // the comparison is relative; a quarter of the pixels
  return s;
}

TEST(Focus, TheLoopReachesTheDenseSweepsBestWithinFivePercent) {
  const TurretSpec s = QuickSpec();
  const int k = s.MirrorIndex("wide");
  SimulatedUnit unit(s, k, s.NominalAxes(k, s.mirrors[k].PlateHeight()), std::vector<MirrorPose>(s.mirrors.size()), 3);
  const FocusResult r = FocusLens(unit, s, {});
  double best = 0, best_focus = 0;
  for (double f = 0.8 * s.mirrors[k].PlateHeight(); f <= 1.6 * s.mirrors[k].PlateHeight(); f += 0.002) {
    const double sh = Sharpness(RenderTurret(s, k, {}, f, 99), s, k);
    if (sh > best) best = sh, best_focus = f;
  }
  EXPECT_GT(r.sharpness, 0.95 * best) << "loop " << r.focus << " m, sweep " << best_focus << " m";
  EXPECT_NEAR(r.focus, best_focus, 0.004);
  EXPECT_LE(r.images, 30);
  // Well away from the plate: the virtual image lies beyond the mirror.
  EXPECT_GT(r.focus, 1.05 * s.mirrors[k].PlateHeight());
}

TEST(Focus, AStuckFocusAxisIsAnErrorNamingIt) {
  const TurretSpec s = QuickSpec();
  SimulatedUnit unit(s, 0, s.NominalAxes(0, 0.10), std::vector<MirrorPose>(s.mirrors.size()), 3);
  unit.sim().sim(AxisId::kFocus).SetFault({true, 0.0});
  try {
    FocusLens(unit, s, {});
    FAIL() << "focused with a stuck focus axis";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "axis focus");
    EXPECT_NE(std::string(e.what()).find("does not change"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hovs::rig
