// The article's closed-form depth: exact on the rig it assumes; on the reference rig (the right unit 0.9 deg
// yawed, 7 mm and 14 mm off the baseline, its mirror tilted) measured against hovs' triangulation.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "depth/article_depth.h"
#include "scenes/scene_config.h"

namespace hovs::depth {
namespace {

TEST(ArticleDepth, ClosedFormIsExactOnTheRigItAssumes) {
  const double b = 0.64;
  for (const Vec3d& p : {Vec3d(1.0, 2.0, -0.5), Vec3d(-3.0, 0.7, -1.2), Vec3d(0.3, -5.0, -2.0), Vec3d(8, 9, -1)}) {
    const ClosedFormDepth d = ArticleClosedForm(b, p, p - Vec3d(b, 0, 0));
    ASSERT_TRUE(d.ok) << p.transpose();
    EXPECT_LT((d.point_left - p).norm(), 1e-12 * p.norm()) << p.transpose();
  }
  EXPECT_FALSE(ArticleClosedForm(b, Vec3d(1, 0, -0.2), Vec3d(1, 0, -0.2)).ok) << "a point on the baseline's line";
}

TEST(ArticleDepth, OnTheReferenceRigTheClosedFormCostsWhatTheMisalignmentMoves) {
  const auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  const auto& units = cfg.description.units;
  const StereoRig rig{AnyModel::Exact(units[0].rig), AnyModel::Exact(units[1].rig),
                      units[1].world_from_mirror.Inverse() * units[0].world_from_mirror};
  const DepthFormulaStudy s = CompareDepthFormulas(rig);
  std::printf("[ figure ] %zu points\n%s", s.points, DepthFormulaMarkdown(s).c_str());
  EXPECT_GT(s.points, 1000u);
  for (const auto& bin : s.by_range) {
    // hovs' own rays locate every point (the exact models, no noise).
    EXPECT_LT(bin.methods[3].max, 1e-6) << bin.name;
    // The closed form on each unit's own azimuths pays for the right unit's yaw; turning the bearings first
    // removes most of it; hovs' triangulation from F1 is better than either.
    EXPECT_GT(bin.methods[0].median, bin.methods[1].median) << bin.name;
    EXPECT_GT(bin.methods[1].median, bin.methods[2].median) << bin.name;
  }
  // The yaw's cost grows with range (the parallax shrinks as 1 / r).
  EXPECT_GT(s.by_range.back().methods[0].median, 5 * s.by_range.front().methods[0].median);
  DepthFormulaOptions bad;
  bad.ranges_m = {-1};
  EXPECT_THROW(CompareDepthFormulas(rig, bad), Error);
}

}  // namespace
}  // namespace hovs::depth
