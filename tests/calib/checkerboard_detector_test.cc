// hovs' own checkerboard detector on the real VMR images (against the reference corners of an independent
// toolbox) and on rendered catadioptric images (against the renderer's exact corners).
#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calib/checkerboard_detector.h"
#include "calib/cross_validation.h"
#include "tests/calib/synthetic_boards.h"
#include "tests/core/test_rigs.h"
#include "core/error.h"

namespace hovs::calib {
namespace {

const std::string kVmr = std::string(HOVS_SHARED_DIR) + "/data/vmr/";

// Nearest detected corner for every reference corner (labelling may differ by a board symmetry).
struct Match {
  Vec2d mean = Vec2d::Zero();
  double rms = 0, worst = 0;
  int matched = 0;
};
Match MatchCorners(const std::vector<Vec2d>& ref, const std::vector<Vec2d>& found, double gate) {
  Match m;
  double ss = 0;
  for (const auto& r : ref) {
    double best = 1e30;
    for (const auto& f : found) best = std::min(best, (f - r).norm());
    if (best > gate) continue;
    for (const auto& f : found)
      if ((f - r).norm() == best) m.mean += f - r;
    ss += best * best, m.worst = std::max(m.worst, best), ++m.matched;
  }
  if (m.matched) m.mean /= m.matched;
  m.rms = m.matched ? std::sqrt(ss / m.matched) : 0;
  return m;
}

struct VmrRun {
  int complete = 0, matched = 0;
  double rms = 0, worst = 0;
  std::vector<BoardObservation> detected;
};

VmrRun DetectVmr(const CheckerboardDetectOptions& o, const std::vector<BoardObservation>& reference) {
  VmrRun run;
  double ss = 0;
  for (const auto& ref : reference) {
    const cv::Mat img = cv::imread(kVmr + ref.image, cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(img.empty()) << ref.image;
    const auto det = DetectCheckerboard(img, o);
    run.complete += det.complete;
    const Match m = MatchCorners(ref.pixels, det.pixels, 3.0);
    std::printf("  %s: %s (%d candidates); %d/%zu reference corners matched, RMS %.4f px, worst %.4f px\n",
                ref.image.c_str(), det.status.c_str(), det.candidates, m.matched, ref.pixels.size(), m.rms, m.worst);
    ss += m.rms * m.rms * m.matched, run.matched += m.matched, run.worst = std::max(run.worst, m.worst);
    run.detected.push_back(ToObservation(det, ref.image));
  }
  run.rms = std::sqrt(ss / std::max(run.matched, 1));
  return run;
}

// The reference corners were refined with a 9 x 9 window (Bouguet's corner finder, the gradient-orthogonality
// method cv::cornerSubPix also uses); with the same window and no edge refinement hovs must agree with them to
// a few hundredths of a pixel. By default hovs then measures each corner from the board's edges
// (calib/checkerboard_edges.h); those corners differ from the reference by about 0.24 px RMS, and they must be
// the better measurement: the same calibration fits them much more closely than the reference corners.
TEST(CheckerboardDetector, FindsTheVmrCornersOfTheReferenceToolbox) {
  const auto reference = LoadCornerCsv(kVmr + "reference_corners.csv");
  ASSERT_EQ(reference.size(), 10u);
  CheckerboardDetectOptions o;
  o.board = {7, 6, 0.030};
  o.subpix_half_window = 4;
  o.corner_refinement = "subpix";
  const VmrRun same = DetectVmr(o, reference);
  std::printf("VMR, 9 x 9 window: %d complete boards, %d corners matched, RMS %.4f px, worst %.4f px\n", same.complete,
              same.matched, same.rms, same.worst);
  EXPECT_EQ(same.complete, 10);
  EXPECT_EQ(same.matched, 420);
  EXPECT_LT(same.rms, 0.05);

  o.subpix_half_window = 0;
  o.corner_refinement = "edges";
  const VmrRun edges = DetectVmr(o, reference);
  std::printf("VMR, from the edges: %d corners matched, RMS %.4f px, worst %.4f px\n", edges.matched, edges.rms,
              edges.worst);
  EXPECT_EQ(edges.matched, 420);
  EXPECT_LT(edges.rms, 0.35);

  PolynomialCalibrationOptions po;
  const auto from_reference = CalibratePolynomial(reference, 1024, 768, po);
  const auto from_detected = CalibratePolynomial(same.detected, 1024, 768, po);
  const auto from_edges = CalibratePolynomial(edges.detected, 1024, 768, po);
  std::printf(
      "VMR calibration RMS: reference corners %.4f px, hovs with the 9 x 9 window %.4f px, hovs from the "
      "edges %.4f px\n",
      from_reference.rms, from_detected.rms, from_edges.rms);
  EXPECT_LT(std::abs(from_detected.rms - from_reference.rms), 0.01);
  EXPECT_LT(from_edges.rms, 0.9 * from_reference.rms);
  EXPECT_LT(from_edges.rms, 0.31);

  // The VMR image is decentred (the unified model's p1, p2 account for all its lead over the polynomial one):
  // with the decentering and the board's flex the polynomial model fits to at most 0.28 px, and the
  // decentering predicts held-out images better (leave-one-image-out), so it is the camera, not overfitting.
  PolynomialCalibrationOptions dc = po;
  dc.board_flex = true, dc.estimate_decentering = true;
  const auto decentred = CalibratePolynomial(edges.detected, 1024, 768, dc);
  PolynomialCalibrationOptions flat_flex = po;
  flat_flex.board_flex = true;
  const auto plain = CalibratePolynomial(edges.detected, 1024, 768, flat_flex);
  const auto cv_plain = CrossValidatePolynomial(edges.detected, 1024, 768, flat_flex, 10, plain.model);
  const auto cv_decentred = CrossValidatePolynomial(edges.detected, 1024, 768, dc, 10, decentred.model);
  std::printf(
      "VMR polynomial with the board's flex: RMS %.4f px (held out %.4f px) without decentering, %.4f px (held out "
      "%.4f px) with it; p1 %.3g, p2 %.3g\n",
      plain.rms, cv_plain.held_out_rms, decentred.rms, cv_decentred.held_out_rms, decentred.model.p1,
      decentred.model.p2);
  EXPECT_LE(decentred.rms, 0.28);
  EXPECT_LT(cv_decentred.held_out_rms, 0.95 * cv_plain.held_out_rms);
}

TEST(CheckerboardDetector, FindsNoBoardInNoise) {
  // Noise holds saddle points that line up into small grids; their squares neither are flat nor alternate.
  CheckerboardDetectOptions o;
  o.board = {7, 5, 0.030};
  for (uint32_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    cv::Mat noise(440, 550, CV_8UC1);
    uint32_t state = seed;
    for (int y = 0; y < noise.rows; ++y)
      for (int x = 0; x < noise.cols; ++x)
        state = state * 1664525u + 1013904223u, noise.at<uint8_t>(y, x) = state >> 24;
    const auto det = DetectCheckerboard(noise, o);
    EXPECT_FALSE(det.found) << "seed " << seed << ": " << det.status;
    // Blurred noise (texture at the scale of small squares) as well.
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
    cv::normalize(noise, noise, 0, 255, cv::NORM_MINMAX);
    const auto blurred = DetectCheckerboard(noise, o);
    EXPECT_FALSE(blurred.found) << "seed " << seed << ", blurred: " << blurred.status;
  }
}

TEST(CheckerboardDetector, ReportsWhyNothingWasFound) {
  CheckerboardDetectOptions o;
  o.board = {7, 6, 0.030};
  const cv::Mat blank(768, 1024, CV_8UC1, cv::Scalar(128));
  const auto none = DetectCheckerboard(blank, o);
  EXPECT_FALSE(none.found);
  EXPECT_NE(none.status.find("no grid"), std::string::npos) << none.status;
  // A board described smaller than it is: refused, not silently cut.
  const cv::Mat img = cv::imread(kVmr + "VMRImage0.jpg", cv::IMREAD_GRAYSCALE);
  o.board = {5, 4, 0.030};
  const auto small = DetectCheckerboard(img, o);
  EXPECT_FALSE(small.found);
  EXPECT_NE(small.status.find("larger than"), std::string::npos) << small.status;
  // Half of the board hidden: a consistent partial grid, labelled like the board (spacing one square).
  o.board = {7, 6, 0.030};
  cv::Mat hidden = img.clone();
  const auto full = DetectCheckerboard(img, o);
  ASSERT_TRUE(full.complete);
  Vec2d mid = Vec2d::Zero();
  for (const auto& p : full.pixels) mid += p / full.pixels.size();
  cv::rectangle(hidden, cv::Point(0, static_cast<int>(mid.y())), cv::Point(1023, 767), cv::Scalar(200), cv::FILLED);
  const auto part = DetectCheckerboard(hidden, o);
  EXPECT_TRUE(part.found) << part.status;
  EXPECT_FALSE(part.complete);
  EXPECT_NE(part.status.find("partial"), std::string::npos) << part.status;
  EXPECT_GE(part.pixels.size(), 12u);
  for (size_t k = 0; k < part.pixels.size(); ++k) {
    double best = 1e30;
    for (const auto& p : full.pixels) best = std::min(best, (p - part.pixels[k]).norm());
    EXPECT_LT(best, 0.2) << "partial corner " << k;
  }
  o.allow_partial = false;
  EXPECT_FALSE(DetectCheckerboard(hidden, o).found);
  EXPECT_THROW(DetectCheckerboard(cv::Mat(), o), Error);
  o.board.square = -1;
  EXPECT_THROW(DetectCheckerboard(img, o), Error);
}

}  // namespace
}  // namespace hovs::calib

namespace hovs::calib {
namespace {

// Boards through the exact reference rig (rows bent into arcs, squares changing size): every corner proved;
// one corner moved half a square along its row, or swapped with its neighbour, is the one removed.
TEST(GridLabels, ProvesCurvedGridsAndRemovesTheMislabelledCorner) {
  const auto obs = SyntheticObservations(test::AlignedRig(), 12, 0.1, 7);
  int removed_total = 0;
  for (const auto& o : obs) {
    std::vector<double> removed;
    double worst = 0;
    auto keep = ProveGridLabels(o.pixels, 7, 5, 0.25, 1.0, &removed, &worst);
    EXPECT_TRUE(removed.empty()) << o.image << ": a good grid lost " << removed.size() << " corners";
    EXPECT_LT(worst, 0.2) << o.image;
    // Corner (3, 2) moved half a square along its row.
    std::vector<Vec2d> moved = o.pixels;
    const int k = 2 * 7 + 3;
    moved[k] += 0.5 * (o.pixels[k + 1] - o.pixels[k]);
    removed.clear();
    keep = ProveGridLabels(moved, 7, 5, 0.25, 1.0, &removed, &worst);
    ASSERT_EQ(removed.size(), 1u) << o.image;
    EXPECT_FALSE(keep[k]);
    // Two corners of a row swapped (a labelling error): both are removed, nothing else.
    std::vector<Vec2d> swapped = o.pixels;
    std::swap(swapped[k], swapped[k + 1]);
    removed.clear();
    keep = ProveGridLabels(swapped, 7, 5, 0.25, 1.0, &removed, &worst);
    EXPECT_EQ(removed.size(), 2u) << o.image;
    EXPECT_FALSE(keep[k]);
    EXPECT_FALSE(keep[k + 1]);
    removed_total += static_cast<int>(removed.size());
  }
  EXPECT_EQ(removed_total, 24);
}

}  // namespace
}  // namespace hovs::calib
