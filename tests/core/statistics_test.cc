#include "core/statistics.h"

#include <gtest/gtest.h>

#include <random>

#include "core/rigid.h"

namespace hovs {
namespace {

TEST(Statistics, AngleBetweenIsExactNearZeroAndHalfTurn) {
  const Vec3d a(1, 0, 0);
  const double tiny = 1e-9;  // rad: acos(cos(1e-9)) would give 0
  EXPECT_NEAR(AngleBetweenDeg(a, Vec3d(std::cos(tiny), std::sin(tiny), 0)), tiny * 180 / M_PI, 1e-20);
  EXPECT_NEAR(AngleBetweenDeg(a, Vec3d(-1, 1e-9, 0)), 180.0, 1e-6);
  EXPECT_NEAR(AngleBetweenDeg(3 * a, Vec3d(0, 2, 0)), 90.0, 1e-12);  // lengths do not matter
}

TEST(Statistics, BestRotationRecoversARotationFromNoisyBearings) {
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0, 1);
  const Mat3<double> truth = QuaternionFromAngleAxis<double>(Vec3d(0.01, -0.02, 0.3)).toRotationMatrix();
  std::vector<std::pair<Vec3d, Vec3d>> pairs;
  for (int k = 0; k < 500; ++k) {
    const Vec3d b = Vec3d(N(rng), N(rng), N(rng)).normalized();
    const Vec3d a = (truth * b + 1e-4 * Vec3d(N(rng), N(rng), N(rng))).normalized();
    pairs.emplace_back(a, b);
  }
  const Mat3<double> R = BestRotation(pairs);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  EXPECT_LT(Eigen::AngleAxisd(R * truth.transpose()).angle(), 2e-5);
  // A mirror image of the bundle is no rotation: the result stays proper.
  for (auto& [a, b] : pairs) a.x() = -a.x();
  EXPECT_NEAR(BestRotation(pairs).determinant(), 1.0, 1e-12);
  EXPECT_TRUE(BestRotation({}).isIdentity());
}

TEST(Statistics, RunningStatsAndMedian) {
  RunningStats s;
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(s.Mean(), 0.0);
  for (double v : {3.0, -1.0, 4.0}) s.Add(v);
  EXPECT_EQ(s.count, 3);
  EXPECT_DOUBLE_EQ(s.Mean(), 2.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(s.Rms(), std::sqrt(26.0 / 3));
  RunningStats negative;
  negative.Add(-2.0);
  EXPECT_EQ(negative.max, -2.0);  // the first value, not 0
  EXPECT_EQ(Median({5, 1, 3}), 3);
  EXPECT_EQ(Median({4, 1, 3, 2}), 3);  // the upper of an even count
  EXPECT_EQ(Median({}), 0);
}

}  // namespace
}  // namespace hovs
