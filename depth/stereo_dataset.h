// A stereo_aruco dataset (two units per frame, one ArUco board) read for stereo calibration: the units, the
// board's corners, each frame's image pair and, when synthetic, the board's true pose; and the marker detection
// of every pair as stereo calibration consumes it.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "depth/stereo_calibration.h"
#include "raytrace/scene.h"
#include "scenes/scene_config.h"

namespace hovs::depth {

struct StereoFrame {
  std::string name;  // "frame<id>"
  std::filesystem::path left_image, right_image;
  std::optional<Rigid3d> world_from_board;  // synthetic datasets
};

struct StereoDataset {
  std::filesystem::path manifest;
  raytrace::CatadioptricUnit left_unit, right_unit;  // the first two units
  scenes::BoardSpec board_spec;
  std::map<int, Vec3d> board;  // corner id -> board frame, metres
  std::vector<StereoFrame> frames;
  // The true right_from_left of the units' mirror frames (exact for a synthetic dataset).
  Rigid3d TrueRightFromLeft() const;
};

// Throws hovs::Error naming the manifest: fewer than two units, no ArUco board, a frame without both images.
StereoDataset LoadStereoDataset(const std::filesystem::path& manifest);

struct StereoDetectOptions {
  MarkerDetectOptions markers;   // its dictionary is the board's
  double marker_check_px = 2.0;  // RejectInconsistentMarkers; 0: keep every marker
};

// What the detector found in one pair.
struct PairDetection {
  std::string pair;
  int left_corners = 0, right_corners = 0, left_from_edges = 0, right_from_edges = 0;
  std::vector<int> inconsistent_left, inconsistent_right;  // markers dropped
};

// Every frame's markers in both images, through each unit's model. `progress` receives each pair's record.
std::vector<StereoPairObservation> DetectStereoPairs(const StereoDataset& dataset, const AnyModel& left,
                                                     const AnyModel& right, const StereoDetectOptions& options,
                                                     std::vector<PairDetection>* detections,
                                                     const std::function<void(const PairDetection&)>& progress = {});

}  // namespace hovs::depth
