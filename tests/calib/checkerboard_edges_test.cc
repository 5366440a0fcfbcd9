// Checkerboard corners from the board's edges (calib/checkerboard_edges.h) on synthetic images with exact
// corners: a board seen under a homography and bent by a radial warp (as the mirror bends straight lines),
// rendered with 8 x 8 samples per pixel, then blurred (Gaussian) and given seeded sensor noise; around the
// board a white paper margin and a textured background. The same corners through cv::cornerSubPix (window
// 0.35 x the square, as the detector) are the comparison.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <optional>
#include <random>

#include "calib/checkerboard_edges.h"

namespace hovs::calib {
namespace {

struct Board {
  int cols = 7, rows = 5;   // inner corners; the board has (cols + 1) x (rows + 1) squares
  Eigen::Matrix3d H, Hinv;  // image (before the warp) from board units (one square = 1)
  double k = 0;             // radial warp about c: p' = c + (p - c) (1 + k |p - c|^2)
  Vec2d c{160, 120};
  Vec2d Warp(const Vec2d& p) const { return c + (p - c) * (1 + k * (p - c).squaredNorm()); }
  Vec2d Unwarp(const Vec2d& q) const {
    Vec2d p = q;
    // A contraction by |k| |p - c|^2 <= 0.03 per step: six steps converge to 1e-9 px.
    for (int i = 0; i < 6 && k != 0; ++i) p = c + (q - c) / (1 + k * (p - c).squaredNorm());
    return p;
  }
  Vec2d Corner(int i, int j) const {  // inner corner (i, j): board point (i + 1, j + 1)
    const Eigen::Vector3d x = H * Eigen::Vector3d(i + 1, j + 1, 1);
    return Warp(Vec2d(x(0) / x(2), x(1) / x(2)));
  }
  double Value(const Vec2d& q) const {
    const Vec2d p = Unwarp(q);
    const Eigen::Vector3d m = Hinv * Eigen::Vector3d(p.x(), p.y(), 1);
    const double u = m(0) / m(2), v = m(1) / m(2);
    if (u >= 0 && v >= 0 && u < cols + 1 && v < rows + 1)
      return (static_cast<int>(u) + static_cast<int>(v)) % 2 ? 220 : 30;
    if (u > -0.5 && v > -0.5 && u < cols + 1.5 && v < rows + 1.5) return 220;  // paper margin
    return 110 + 50 * std::sin(0.9 * q.x()) * std::cos(0.7 * q.y());           // background
  }
  cv::Mat Render(int w, int h, double blur_sigma, double noise_sigma, std::mt19937* rng) const {
    cv::Mat img(h, w, CV_64FC1);
    const int ss = 8;  // samples per pixel and axis (box filter)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double s = 0;
        for (int sy = 0; sy < ss; ++sy)
          for (int sx = 0; sx < ss; ++sx) s += Value(Vec2d(x - 0.5 + (sx + 0.5) / ss, y - 0.5 + (sy + 0.5) / ss));
        img.at<double>(y, x) = s / (ss * ss);
      }
    if (blur_sigma > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), blur_sigma);
    std::normal_distribution<double> N(0, noise_sigma);
    cv::Mat out(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        out.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(img.at<double>(y, x) + (noise_sigma > 0 ? N(*rng) : 0));
    return out;
  }
};

Board MakeBoard(std::mt19937* rng, double square, double k) {
  std::uniform_real_distribution<double> U(-1, 1);
  Board b;
  b.k = k;
  const double a = 0.5 * U(*rng);
  // Rotation and scale about the board's centre, placed at the image centre, with some perspective.
  const Vec2d mid(0.5 * (b.cols + 1), 0.5 * (b.rows + 1));
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity(), P = Eigen::Matrix3d::Identity(), R;
  T(0, 2) = -mid.x(), T(1, 2) = -mid.y();
  P(2, 0) = 0.03 * U(*rng), P(2, 1) = 0.03 * U(*rng);
  R << std::cos(a) * square, -std::sin(a) * square, b.c.x(), std::sin(a) * square, std::cos(a) * square, b.c.y(), 0, 0,
      1;
  b.H = R * P * T;
  b.Hinv = b.H.inverse();
  return b;
}

struct Result {
  double edges_rms = 0, subpix_rms = 0, edges_worst = 0;
  int refined = 0, total = 0;
};

Result RunBoards(double square, double k, double blur, double noise, int boards, unsigned seed) {
  std::mt19937 rng(seed);
  Result r;
  double se = 0, ss = 0;
  for (int n = 0; n < boards; ++n) {
    const Board b = MakeBoard(&rng, square, k);
    const cv::Mat img = b.Render(320, 240, blur, noise, &rng);
    std::vector<std::optional<Vec2d>> grid;
    std::vector<Vec2d> truth;
    std::vector<cv::Point2f> sub;
    std::uniform_real_distribution<double> U(-0.7, 0.7);
    for (int j = 0; j < b.rows; ++j)
      for (int i = 0; i < b.cols; ++i) {
        truth.push_back(b.Corner(i, j));
        sub.emplace_back(static_cast<float>(truth.back().x() + U(rng)), static_cast<float>(truth.back().y() + U(rng)));
      }
    const int w = std::clamp(static_cast<int>(std::lround(0.35 * square)), 2, 11);
    cv::cornerSubPix(img, sub, cv::Size(w, w), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.001));
    for (const auto& p : sub) grid.emplace_back(Vec2d(p.x, p.y));
    const auto refined = RefineCheckerboardCornersByEdges(img, b.cols, b.rows, &grid);
    for (size_t q = 0; q < truth.size(); ++q) {
      const double de = (*grid[q] - truth[q]).norm(), ds = (Vec2d(sub[q].x, sub[q].y) - truth[q]).norm();
      se += de * de, ss += ds * ds, r.edges_worst = std::max(r.edges_worst, de);
      r.refined += refined[q], ++r.total;
    }
  }
  r.edges_rms = std::sqrt(se / r.total), r.subpix_rms = std::sqrt(ss / r.total);
  return r;
}

void Report(const char* what, const Result& r) {
  std::printf("[ figure ] %s: %d of %d corners from edges, RMS %.4f px (worst %.4f px), cornerSubPix %.4f px\n", what,
              r.refined, r.total, r.edges_rms, r.edges_worst, r.subpix_rms);
}

TEST(CheckerboardEdges, SharpBentBoardCornersToAHundredthOfAPixel) {
  const Result r = RunBoards(24, 2e-6, 0, 0, 3, 7);
  Report("24 px squares, bent, no blur or noise", r);
  EXPECT_EQ(r.refined, r.total);
  EXPECT_LT(r.edges_rms, 0.02);
  EXPECT_LT(r.edges_rms, 0.5 * r.subpix_rms);
}

TEST(CheckerboardEdges, BlurAndNoiseAverageOutAlongTheLines) {
  // The situation of the real VMR images: ~20 px squares, a blur of about a pixel, JPEG-like noise.
  // (Measured apart: blur alone 0.005 px, noise alone 0.018 px vs cornerSubPix's 0.053 px.)
  const Result r = RunBoards(20, 2e-6, 1.0, 4.0, 6, 11);
  Report("20 px squares, bent, blur 1 px, noise 4 grey levels", r);
  EXPECT_GE(r.refined, 0.95 * r.total);
  EXPECT_LT(r.edges_rms, 0.035);
  EXPECT_LT(r.edges_rms, 0.7 * r.subpix_rms);
}

TEST(CheckerboardEdges, SmallSquaresKeepTheirCorners) {
  std::mt19937 rng(3);
  const Board b = MakeBoard(&rng, 4, 0);
  const cv::Mat img = b.Render(320, 240, 0, 0, &rng);
  std::vector<std::optional<Vec2d>> grid;
  for (int j = 0; j < b.rows; ++j)
    for (int i = 0; i < b.cols; ++i) grid.emplace_back(b.Corner(i, j) + Vec2d(0.3, -0.2));
  grid[3].reset();  // a corner not found stays not found
  const auto before = grid;
  const auto refined = RefineCheckerboardCornersByEdges(img, b.cols, b.rows, &grid);
  for (size_t q = 0; q < grid.size(); ++q) {
    EXPECT_FALSE(refined[q]);
    EXPECT_EQ(grid[q].has_value(), before[q].has_value());
    if (grid[q]) { EXPECT_EQ(*grid[q], *before[q]); }
  }
}

}  // namespace
}  // namespace hovs::calib
