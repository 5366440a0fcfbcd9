// Rendered datasets and the dataset manifest. The manifest (dataset.json) is the one format shared by synthetic
// renders and real captures: frames, each with one view per unit (image, and ground truth when there is any),
// the rig, the boards, the config and versions that made it.
//
// dataset.json:
//   {"format": "hovs-dataset", "version": 1, "kind": "...", "name": "...", "seed": N,
//    "units": [unit...], "frames": [{"id": 0, "views": [{"unit": "unit0", "image": "images/...",
//      "ground_truth": {"exr": "truth/....exr", "sidecar": "truth/....json"}}]}],
//    "generator": {...}, "versions": {...}}
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include "scenes/scene_config.h"

namespace hovs::scenes {

struct DatasetOptions {
  std::string kind = "mono_calibration";  // mono_calibration | render
  int count = 9;                          // frames
  uint64_t seed = 1;                      // board poses (the render seed comes from the scene's render options)
  BoardSpec board;                        // the calibration board (default: 8 x 6 squares of 30 mm: 7 x 5 corners)
  double min_distance = 0.3, max_distance = 0.6;   // board centre from the viewpoint, m
  double min_elevation_deg = -55, max_elevation_deg = -12;
  double max_tilt_deg = 35;                        // board tilt away from facing the viewpoint
  double edge_margin_px = 8;                       // corners at least this far inside the valid annulus
  bool progress = false;
  void Check(const std::string& where) const;
};

// Renders every unit of the scene once: writes out/ (staged) with images/, truth/ and dataset.json.
void RenderSceneFolder(const SceneConfig& scene, const std::filesystem::path& out, bool progress,
                       const std::map<std::string, std::string>& versions);

// A monocular calibration set: board poses drawn so that every corner is visible in unit 0.
void WriteCalibrationDataset(const SceneConfig& base, const DatasetOptions& options, const std::filesystem::path& out,
                             const std::map<std::string, std::string>& versions);

// Board poses for a calibration set (exposed for tests): each keeps every corner visible.
std::vector<Rigid3d> DrawBoardPoses(const SceneConfig& base, const DatasetOptions& options);

}  // namespace hovs::scenes
