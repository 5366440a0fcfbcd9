// The report of a stereo calibration: stereo.json (relative pose, standard deviations, per-pair errors, detection
// counts, the article's 3-D residual method beside it and, for a synthetic dataset, the errors against the true
// rig and the sparse depth), stereo.yaml (OpenCV FileStorage: R, T), sparse_depth.csv, summary.txt, the
// reprojection figure of every pair and unit (the article's Fig. 28), the plots of sparse depth error against
// range and against the angle to the baseline, and index.html.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "depth/evaluation.h"
#include "depth/stereo_calibration.h"
#include "depth/stereo_dataset.h"

namespace hovs::depth {

struct StereoRun {
  const StereoDataset* dataset = nullptr;
  const AnyModel* left = nullptr;
  const AnyModel* right = nullptr;
  std::vector<StereoPairObservation> pairs;
  std::vector<PairDetection> detections;
  StereoCalibrationOptions options;
  std::string corner_refinement;
  StereoCalibration calibration;
  std::optional<StereoCalibration> article_3d;  // the article's 3-D residual method on the same corners
  std::string article_3d_error;                 // why it failed, when it did
  PoseError pose_error, article_3d_pose_error;
  SparseDepthEvaluation sparse;
};

// Calibrates (both methods) and evaluates against the dataset's truth.
StereoRun RunStereoCalibration(const StereoDataset& dataset, const AnyModel& left, const AnyModel& right,
                               std::vector<StereoPairObservation> pairs, std::vector<PairDetection> detections,
                               const StereoCalibrationOptions& options, const std::string& corner_refinement);

// stereo.json without "tool", "versions" and "dataset" (the caller's).
nlohmann::json StereoRunJson(const StereoRun& run);
std::string StereoRunSummary(const StereoRun& run);

// Writes every file of the report into `folder`. The plots need a display (results::CanRender); without one they
// are left out and the page says so.
void WriteStereoReport(const std::filesystem::path& folder, const StereoRun& run, const nlohmann::json& record);

}  // namespace hovs::depth
