// Marker corners from the marker's edges (depth/marker_edges.h) on synthetic images with exact corners: a
// 6 x 6-bit marker seen under a homography, optionally bent by a radial warp (as the mirror bends straight
// lines), rendered with 8 x 8 samples per pixel (box filter, no other blur); optionally at the board's edge
// (a narrow paper margin, then a textured ground).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <opencv2/core.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>

#include "depth/marker_edges.h"

namespace hovs::depth {
namespace {

struct Scene {
  Eigen::Matrix3d H;  // image (before the warp) from marker coordinates in [0, 1]^2
  Eigen::Matrix3d Hinv;
  double margin = 0;  // > 0: the paper ends this far (marker units) left of and above the marker
  double k = 0;       // radial warp about (cx, cy): p' = c + (p - c) (1 + k |p - c|^2)
  Vec2d c{100, 100};
  std::array<int, 36> bits{};
  Vec2d Warp(const Vec2d& p) const { return c + (p - c) * (1 + k * (p - c).squaredNorm()); }
  Vec2d Unwarp(const Vec2d& q) const {  // fixed point: the warp is mild
    Vec2d p = q;
    if (k == 0) return p;
    for (int i = 0; i < 12; ++i) p = c + (q - c) / (1 + k * (p - c).squaredNorm());
    return p;
  }
  Vec2d Corner(int j) const {  // marker corners (0,0) (1,0) (1,1) (0,1): one consistent order
    const Eigen::Vector3d m(j == 1 || j == 2 ? 1 : 0, j >= 2 ? 1 : 0, 1);
    const Eigen::Vector3d x = H * m;
    return Warp(Vec2d(x(0) / x(2), x(1) / x(2)));
  }
  double Value(const Vec2d& q) const {
    const Vec2d p = Unwarp(q);
    const Eigen::Vector3d m = Hinv * Eigen::Vector3d(p.x(), p.y(), 1);
    const double u = m(0) / m(2), v = m(1) / m(2);
    if (u < 0 || v < 0 || u >= 1 || v >= 1) {
      if (margin > 0 && (u < -margin || v < -margin)) return 120 + 40 * std::sin(37 * u) * std::cos(23 * v);  // ground
      return 235;                                                                                             // paper
    }
    const int i = static_cast<int>(u * 8), j = static_cast<int>(v * 8);
    if (i == 0 || j == 0 || i == 7 || j == 7) return 15;  // border
    return bits[(j - 1) * 6 + (i - 1)] ? 235 : 15;
  }
  cv::Mat Render(int w, int h) const {
    cv::Mat img(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double s = 0;
        for (int sy = 0; sy < 8; ++sy)
          for (int sx = 0; sx < 8; ++sx) s += Value(Vec2d(x - 0.5 + (sx + 0.5) / 8, y - 0.5 + (sy + 0.5) / 8));
        img.at<uint8_t>(y, x) = static_cast<uint8_t>(std::lround(s / 64));
      }
    return img;
  }
};

Scene MakeScene(std::mt19937* rng, double size, double k) {
  std::uniform_real_distribution<double> U(-1, 1);
  Scene s;
  s.k = k;
  for (auto& b : s.bits) b = (*rng)() % 2;
  // A square of the given size around the centre, rotated, with some perspective.
  const double a = 0.7 * U(*rng);
  Eigen::Matrix3d R;
  R << std::cos(a) * size, -std::sin(a) * size, 100 - 0.5 * size * (std::cos(a) - std::sin(a)), std::sin(a) * size,
      std::cos(a) * size, 100 - 0.5 * size * (std::sin(a) + std::cos(a)), 0, 0, 1;
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity();
  P(2, 0) = 0.15 * U(*rng), P(2, 1) = 0.15 * U(*rng);
  // Perspective in marker coordinates about the marker's centre keeps it near the image centre.
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity(), Ti = Eigen::Matrix3d::Identity();
  T(0, 2) = T(1, 2) = 0.5, Ti(0, 2) = Ti(1, 2) = -0.5;
  s.H = R * T * P * Ti;
  s.Hinv = s.H.inverse();
  return s;
}

struct Result {
  double rms = 0, worst = 0;
  int refined = 0, total = 0;
};

Result Measure(double size, double k, int trials, unsigned seed, double guide_noise_px, double margin = 0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, guide_noise_px);
  Result r;
  double s2 = 0;
  for (int t = 0; t < trials; ++t) {
    Scene s = MakeScene(&rng, size, k);
    s.margin = margin;
    const cv::Mat img = s.Render(200, 200);
    std::array<Vec2d, 4> c, truth;
    for (int j = 0; j < 4; ++j) truth[j] = s.Corner(j), c[j] = truth[j] + Vec2d(N(rng), N(rng));
    const auto ok = RefineMarkerCornersByEdges(img, &c, {});
    for (int j = 0; j < 4; ++j) {
      ++r.total;
      if (!ok[j]) continue;
      ++r.refined;
      const double e = (c[j] - truth[j]).norm();
      s2 += e * e, r.worst = std::max(r.worst, e);
    }
  }
  r.rms = std::sqrt(s2 / std::max(1, r.refined));
  return r;
}

TEST(MarkerEdges, CornersOfStraightAndBentMarkers) {
  // Guides 0.3 px off (what a corner window or the unwrapped view's detection gives).
  const Result straight = Measure(60, 0, 6, 3, 0.3);
  std::printf("[ figure ] 60 px markers, straight sides: %d of %d corners, RMS %.4f px, worst %.4f px\n",
              straight.refined, straight.total, straight.rms, straight.worst);
  EXPECT_EQ(straight.refined, straight.total);
  EXPECT_LE(straight.rms, 0.03);
  EXPECT_LE(straight.worst, 0.08);
  // Sides bent by about 1.5 px over their length.
  const Result bent = Measure(60, 2e-5, 6, 4, 0.3);
  std::printf("[ figure ] 60 px markers, bent sides: %d of %d corners, RMS %.4f px, worst %.4f px\n", bent.refined,
              bent.total, bent.rms, bent.worst);
  EXPECT_EQ(bent.refined, bent.total);
  EXPECT_LE(bent.rms, 0.05);
  // A marker at the board's edge: 0.8 cell of paper, then a textured ground; guides off by 0.3 and 1.5 px
  // (the unwrapped view's detection near the rim).
  for (const double guide : {0.3, 1.5}) {
    const Result edge = Measure(48, 0, 6, 6, guide, 0.1);
    std::printf(
        "[ figure ] 48 px markers at the board's edge, guides %.1f px off: %d of %d corners, RMS %.4f px, "
        "worst %.4f px\n",
        guide, edge.refined, edge.total, edge.rms, edge.worst);
    EXPECT_GE(edge.refined, edge.total * 3 / 4);
    EXPECT_LE(edge.rms, 0.03);
    EXPECT_LE(edge.worst, 0.08);
  }
  // Small markers (3 px cells).
  const Result small = Measure(24, 0, 6, 5, 0.2);
  std::printf("[ figure ] 24 px markers: %d of %d corners, RMS %.4f px, worst %.4f px\n", small.refined, small.total,
              small.rms, small.worst);
  EXPECT_GE(small.refined, small.total * 3 / 4);
  EXPECT_LE(small.rms, 0.08);
}

TEST(MarkerEdges, LeavesMarkersTooSmallOrWithoutContrastAlone) {
  std::mt19937 rng(9);
  const Scene s = MakeScene(&rng, 14, 0);  // 1.75 px cells: below min_cell_px
  const cv::Mat img = s.Render(200, 200);
  std::array<Vec2d, 4> c;
  for (int j = 0; j < 4; ++j) c[j] = s.Corner(j);
  const auto before = c;
  const auto ok = RefineMarkerCornersByEdges(img, &c, {});
  for (int j = 0; j < 4; ++j) {
    EXPECT_FALSE(ok[j]);
    EXPECT_EQ(c[j], before[j]);
  }
  // A flat image: nothing to measure.
  const cv::Mat flat(200, 200, CV_8UC1, cv::Scalar(128));
  const Scene big = MakeScene(&rng, 60, 0);
  for (int j = 0; j < 4; ++j) c[j] = big.Corner(j);
  const auto ok2 = RefineMarkerCornersByEdges(flat, &c, {});
  for (int j = 0; j < 4; ++j) EXPECT_FALSE(ok2[j]);
}

}  // namespace
}  // namespace hovs::depth
