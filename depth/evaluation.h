// Stereo calibration and sparse depth against the truth of a synthetic stereo dataset: the relative pose's
// errors, and every marker corner seen by both units triangulated with the calibrated pose and models against its
// true range. Used by hovs stereo-calibrate and hovs validate; plots and tables read the same records.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "depth/stereo.h"
#include "depth/stereo_calibration.h"
#include "depth/stereo_dataset.h"

namespace hovs::depth {

struct PoseError {
  double true_baseline_m = 0;
  double baseline_error_mm = 0;  // calibrated minus true
  double translation_error_mm = 0;
  double rotation_error_deg = 0;
};

PoseError CompareWithTruth(const Rigid3d& right_from_left, double baseline, const Rigid3d& truth);

// One triangulated corner: where it is (range, angle between its direction and the baseline, from the left
// viewpoint), its error, what the geometry predicts for 0.1 px of corner noise, the rays' gap, and each unit's
// corner error against the board's true pose projected through that unit's model.
struct SparseDepthPoint {
  std::string pair;
  int corner = 0;
  double rel_error = 0;  // (triangulated - true) / true range, signed
  double range_m = 0, angle_to_baseline_deg = 0;
  double predicted_sigma_rel = 0, ray_gap_mm = 0;
  double left_corner_error_px = -1, right_corner_error_px = -1;  // -1: the model cannot project the point
  bool left_from_edges = false, right_from_edges = false;
};

struct SparseDepthEvaluation {
  std::vector<SparseDepthPoint> points;
  int excluded_outlier_corners = 0;  // corners the calibration rejected: not triangulated
};

// Frames without a true board pose are skipped (a real dataset gives no points).
SparseDepthEvaluation EvaluateSparseDepth(const StereoDataset& dataset, const AnyModel& left, const AnyModel& right,
                                          const StereoCalibration& calibration,
                                          const std::vector<StereoPairObservation>& pairs);

// Points at least this far from the baseline direction (and from its opposite) are "conditioned": nearer, a pixel
// of disparity is a large fraction of the range, and dense depth masks them too.
inline constexpr double kConditionedAngleDeg = 15;

// The record of stereo.json's "sparse_depth": points, RMS / median / 95th percentile / worst |relative error|,
// the range bands, the ten worst points, and the same for the conditioned points. Null without points.
nlohmann::json SparseDepthJson(const SparseDepthEvaluation& evaluation);

// Every point as CSV (one header line), for plots and other tools.
std::string SparseDepthCsv(const SparseDepthEvaluation& evaluation);

// Dense depth against a range image (the renderer's Z channel of the left unit, `truth_width` pixels a row): each
// rectified pixel's true range read at its source pixel, by distance band (1-2, 2-4, 4-8, 8-16, 16-64 m).
struct DenseBand {
  double lo = 0, hi = 0;
  int pixels = 0;           // with ground truth in the band
  std::vector<double> rel;  // sorted |relative error| of the valid ones
  double ValidFraction() const { return double(rel.size()) / std::max(1, pixels); }
  double Median() const;                      // NaN without valid pixels
  double WithinFraction(double limit) const;  // of all pixels in the band
};

struct DenseDepthEvaluation {
  std::vector<DenseBand> bands;
  // |relative error| per rectified pixel as RGB: 0 (blue) to 5 % and above (red); black where the depth is
  // masked, grey where there is no ground truth.
  std::vector<float> error_map;
};

DenseDepthEvaluation EvaluateDenseDepth(const Rectification& rect, const DenseDepth& depth,
                                        const std::vector<float>& truth_range, int truth_width);
nlohmann::json DenseBandsJson(const DenseDepthEvaluation& evaluation);
std::string DenseBandsTable(const DenseDepthEvaluation& evaluation);  // the text table hovs depth prints

// At most max_points valid pixels, evenly spaced in raster order, as coloured points (left mirror frame) and
// their range sigmas.
void SubsampledCloud(const Rectification& rect, const DenseDepth& depth, const unwrap::Image8& left_rect,
                     int max_points, std::vector<ColouredPoint>* points, std::vector<float>* sigmas);

}  // namespace hovs::depth
