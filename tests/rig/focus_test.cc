// The focus loop against a dense sweep of the same sharpness measure, and the flat-sharpness error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

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
  // The dense sweep's own score: each band against its best over the sweep, the worst band.
  std::vector<double> foci;
  std::vector<std::vector<double>> bands;
  for (double f = 0.8 * s.mirrors[k].PlateHeight(); f <= 1.6 * s.mirrors[k].PlateHeight(); f += 0.002) {
    foci.push_back(f);
    bands.push_back(BandSharpness(RenderTurret(s, k, {}, f, 99), s, k));
  }
  std::vector<double> best_band(kFocusBands, 0.0);
  for (const auto& v : bands)
    for (int b = 0; b < kFocusBands; ++b) best_band[b] = std::max(best_band[b], v[b]);
  double best = 0, best_focus = 0;
  for (size_t i = 0; i < foci.size(); ++i) {
    double score = HUGE_VAL;
    for (int b = 0; b < kFocusBands; ++b) score = std::min(score, bands[i][b] / best_band[b]);
    if (score > best) best = score, best_focus = foci[i];
  }
  const std::vector<double> at_loop = BandSharpness(RenderTurret(s, k, {}, r.focus, 99), s, k);
  double loop_score = HUGE_VAL;
  for (int b = 0; b < kFocusBands; ++b) loop_score = std::min(loop_score, at_loop[b] / best_band[b]);
  EXPECT_GT(loop_score, 0.95 * best) << "loop " << r.focus << " m, sweep " << best_focus << " m";
  EXPECT_NEAR(r.focus, best_focus, 0.004);
  EXPECT_LE(r.images, 30);
  // Well away from the plate: the virtual image lies beyond the mirror.
  EXPECT_GT(r.focus, 1.05 * s.mirrors[k].PlateHeight());
  // The optics' prediction from the machine's lens (f/4): the loop lands inside the mirror's depth of focus.
  const auto p = PredictFocus(s, k);
  ASSERT_TRUE(p.has_value());
  EXPECT_TRUE(p->Contains(r.focus)) << "loop " << r.focus << " m, predicted " << p->best << " m in [" << p->near << ", "
                                    << p->far << "]";
  EXPECT_NEAR(p->tolerance_px, 1.0, 1e-12);
  EXPECT_LT(p->near, p->best);
  EXPECT_GT(p->far, p->best);
}

TEST(Focus, ThePredictionFollowsTheLens) {
  TurretSpec s = QuickSpec();
  const int k = s.MirrorIndex("reference");
  const auto f4 = PredictFocus(s, k);
  ASSERT_TRUE(f4.has_value());
  // A smaller aperture blurs less and focuses over a deeper range; a pinhole has nothing to predict.
  s.lens->f_number = 8;
  const auto f8 = PredictFocus(s, k);
  EXPECT_LT(f8->worst_rms_px, 0.6 * f4->worst_rms_px);
  EXPECT_GT(1 / f8->near - 1 / f8->far, 1 / f4->near - 1 / f4->far);  // in vergence
  s.lens.reset();
  EXPECT_FALSE(PredictFocus(s, k).has_value());
  EXPECT_EQ(FocusAgainstPrediction(s, k, 0.15), "");
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
