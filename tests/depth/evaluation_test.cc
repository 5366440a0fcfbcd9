// depth/evaluation.h: the pose error against known offsets; sparse depth of exact corners through the exact
// models (errors at rounding level) and of corners moved by a known amount; the record's statistics.
#include "depth/evaluation.h"

#include <gtest/gtest.h>

#include "core/statistics.h"
#include "scenes/scene_config.h"

namespace hovs::depth {
namespace {

TEST(DepthEvaluation, PoseErrorOfAKnownOffset) {
  const Rigid3d truth(QuaternionFromAngleAxis<double>(Vec3d(0, 0, 0.1)), Vec3d(-0.64, 0.01, 0));
  const Rigid3d turned(QuaternionFromAngleAxis<double>(Vec3d(0, 0.001, 0)) * truth.rotation,
                       truth.translation + Vec3d(0.002, 0, 0));
  const PoseError e = CompareWithTruth(turned, turned.translation.norm(), truth);
  EXPECT_NEAR(e.true_baseline_m, truth.translation.norm(), 1e-15);
  EXPECT_NEAR(e.translation_error_mm, 2.0, 1e-9);
  EXPECT_NEAR(e.baseline_error_mm, 1e3 * (turned.translation.norm() - truth.translation.norm()), 1e-9);
  EXPECT_NEAR(e.rotation_error_deg, 0.001 * 180 / M_PI, 1e-9);
}

// A stereo dataset of the reference rig with one board pose, the corners projected exactly through each unit.
struct Fixture {
  StereoDataset dataset;
  std::vector<StereoPairObservation> pairs;
  StereoCalibration calibration;
};

Fixture ExactFixture(double left_shift_px) {
  const auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  Fixture f;
  f.dataset.left_unit = cfg.description.units[0], f.dataset.right_unit = cfg.description.units[1];
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 5; ++k) f.dataset.board[i * 5 + k] = Vec3d(0.05 * i, 0.05 * k, 0);
  // The board 2.5 m in front of the rig, upright, beside the baseline.
  const Rigid3d world_from_left = f.dataset.left_unit.world_from_mirror;
  const Rigid3d left_from_board(QuaternionFromAngleAxis<double>(Vec3d(M_PI / 2, 0, 0)), Vec3d(-0.1, 2.5, -0.4));
  f.dataset.frames.push_back({"frame0", "", "", world_from_left * left_from_board});
  f.calibration.right_from_left = f.dataset.TrueRightFromLeft();
  f.calibration.baseline = f.calibration.right_from_left.translation.norm();
  StereoPairObservation p;
  p.name = "frame0";
  for (const auto& [id, b] : f.dataset.board) {
    const Vec3d X = left_from_board * b;
    Vec2d l, r;
    if (f.dataset.left_unit.rig.ImgFromMirror(X, &l) != ProjectionStatus::kOk) continue;
    if (f.dataset.right_unit.rig.ImgFromMirror(f.calibration.right_from_left * X, &r) != ProjectionStatus::kOk)
      continue;
    p.left.push_back({id, l + Vec2d(left_shift_px, 0), true});
    p.right.push_back({id, r, false});
  }
  f.pairs.push_back(p);
  return f;
}

TEST(DepthEvaluation, ExactCornersThroughExactModelsGiveExactRanges) {
  const Fixture f = ExactFixture(0);
  const AnyModel left = AnyModel::Exact(f.dataset.left_unit.rig), right = AnyModel::Exact(f.dataset.right_unit.rig);
  const SparseDepthEvaluation e = EvaluateSparseDepth(f.dataset, left, right, f.calibration, f.pairs);
  ASSERT_EQ(e.points.size(), 30u);
  for (const auto& p : e.points) {
    EXPECT_LT(std::abs(p.rel_error), 1e-9) << p.corner;
    EXPECT_LT(p.left_corner_error_px, 1e-6);
    EXPECT_GT(p.range_m, 2.0);
    EXPECT_TRUE(p.left_from_edges && !p.right_from_edges);
  }
  // A corner the calibration rejected is left out and counted.
  Fixture g = f;
  g.calibration.outliers.push_back({"frame0", "right", 7, 3.0});
  EXPECT_EQ(EvaluateSparseDepth(g.dataset, left, right, g.calibration, g.pairs).excluded_outlier_corners, 1);
}

TEST(DepthEvaluation, AShiftedCornerShowsInTheCornerErrorAndTheRange) {
  const Fixture f = ExactFixture(0.5);
  const AnyModel left = AnyModel::Exact(f.dataset.left_unit.rig), right = AnyModel::Exact(f.dataset.right_unit.rig);
  const SparseDepthEvaluation e = EvaluateSparseDepth(f.dataset, left, right, f.calibration, f.pairs);
  ASSERT_FALSE(e.points.empty());
  for (const auto& p : e.points) {
    EXPECT_NEAR(p.left_corner_error_px, 0.5, 1e-6);
    EXPECT_GT(std::abs(p.rel_error), 1e-5);
    EXPECT_LT(std::abs(p.rel_error), 0.1);
  }
}

TEST(DepthEvaluation, RecordStatistics) {
  SparseDepthEvaluation e;
  // Ten points at 0.5-4.5 m; the two at 5 and 175 deg from the baseline are the worst.
  for (int i = 0; i < 10; ++i) {
    SparseDepthPoint p;
    p.pair = "frame0", p.corner = i;
    p.range_m = 0.5 + 0.45 * i;
    p.angle_to_baseline_deg = i == 3 ? 5 : i == 8 ? 175 : 90;
    p.rel_error = (i == 3 || i == 8 ? -0.05 : 0.001 * (i + 1));
    e.points.push_back(p);
  }
  const nlohmann::json j = SparseDepthJson(e);
  EXPECT_EQ(j["points"], 10);
  EXPECT_DOUBLE_EQ(j["max_rel_error"].get<double>(), 0.05);
  EXPECT_EQ(j["worst_points"][0]["corner"], 3);  // stable: the first of equal errors
  EXPECT_EQ(j["worst_points"][1]["corner"], 8);
  EXPECT_DOUBLE_EQ(j["conditioned"]["max_rel_error"].get<double>(), 0.010);
  EXPECT_EQ(j["conditioned"]["points"], 8);
  double band_points = 0;
  for (const auto& b : j["bands"]) band_points += b["points"].get<double>();
  EXPECT_EQ(band_points, 10);
  EXPECT_TRUE(SparseDepthJson({}).is_null());
  const std::string csv = SparseDepthCsv(e);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 11);
}

}  // namespace
}  // namespace hovs::depth
