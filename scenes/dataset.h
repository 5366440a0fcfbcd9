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
#include <vector>

#include "scenes/scene_config.h"

namespace hovs::scenes {

struct DatasetOptions {
  // mono_calibration: a checkerboard seen whole by unit 0 (the article's 9 images of 7 x 5 corners);
  // stereo_aruco: a 1.2 m ArUco marker board seen by every unit at once (the article's 12 pairs);
  // depth_sequence: the scene as it is (street, room), every unit rendered per frame while the rig moves
  // step_m per frame along heading_deg (world, from +x towards +y) and turns yaw_step_deg per frame about the
  // vertical through the units' centroid (a vehicle driving through the scene).
  std::string kind = "mono_calibration";
  int count = 9;      // frames
  uint64_t seed = 1;  // board poses (the render seed comes from the scene's render options)
  BoardSpec board;    // the calibration board (default: 8 x 6 squares of 30 mm: 7 x 5 corners)
  double min_distance = 0.3, max_distance = 0.6;  // board centre from the viewpoint, m
  double min_elevation_deg = -55, max_elevation_deg = -12;
  double max_tilt_deg = 35;                                // board tilt away from facing the viewpoint
  double edge_margin_px = 8;                               // corners at least this far inside the valid annulus
  double min_visible_fraction = 1.0;                       // of the board's corners, in every unit that must see it
  double step_m = 0.5, heading_deg = 0, yaw_step_deg = 0;  // depth_sequence
  bool progress = false;
  // A shard of the set (any kind): frames [index count / shards, (index + 1) count / shards)
  // of the same poses (all drawn, only these rendered; each frame seeded by its index), with "shard" in the
  // manifest. MergeDatasetShards joins the shards into the set one process writes.
  int shard_index = 0, shard_count = 1;
  // Resume a killed run of the same command (or an interrupted one that itself ran with resume): the frames its
  // journal lists whole, with files matching their checksums, are kept; the rest is rendered (frame_journal.h).
  bool resume = false;
  void Check(const std::string& where) const;
  // Defaults for a kind (board, count, distances, visibility).
  static DatasetOptions ForKind(const std::string& kind);
};

// Renders every unit of the scene once: writes out/ (staged) with images/, truth/ and dataset.json.
void RenderSceneFolder(const SceneConfig& scene, const std::filesystem::path& out, bool progress,
                       const std::map<std::string, std::string>& versions);

// A board dataset (mono_calibration or stereo_aruco) and a depth sequence: each frame entry of the manifest
// carries "checksums" ({relative path: "fnv1a64:..."}) of its files. A killed run leaves its staging folder for
// a later --resume; with resume set, an interrupt (SIGINT, SIGTERM) between frames leaves it too, while without it
// an interrupt removes it and ends the process by the signal (core/interrupt.h).
//
// A board dataset (mono_calibration or stereo_aruco): board poses drawn so that the board is visible as the
// kind asks, every unit that must see it rendered per frame, with ground truth.
void WriteCalibrationDataset(const SceneConfig& base, const DatasetOptions& options, const std::filesystem::path& out,
                             const std::map<std::string, std::string>& versions);

// Joins the shard folders of one dataset (each written with shard_count = their number) into `out`: the
// images, ground truth and a manifest equal to one process's apart from the render timings. Throws hovs::Error
// naming the shard that does not belong: another config, seed, kind or library version, a shard missing or given
// twice, a file missing.
void MergeDatasetShards(const std::vector<std::filesystem::path>& shards, const std::filesystem::path& out);

// A depth_sequence dataset: per frame every unit moved by world_from_rig(frame) (recorded in the frame entry as
// "world_from_rig"; the manifest's units are frame 0's), rendered with ground truth; the scene's own objects
// and boards stay where they are.
void WriteDepthSequence(const SceneConfig& base, const DatasetOptions& options, const std::filesystem::path& out,
                        const std::map<std::string, std::string>& versions);
// The rig motion of frame `frame` of a depth_sequence (exposed for tests).
Rigid3d WorldFromRigAt(const SceneConfig& base, const DatasetOptions& options, int frame);

// Board poses for a dataset (exposed for tests): each keeps at least min_visible_fraction of the corners
// visible (inside the valid annulus by edge_margin_px) in unit 0 (mono) or in every unit (stereo), and the board
// passes through nothing else in the scene (the ground, boxes, the units).
std::vector<Rigid3d> DrawBoardPoses(const SceneConfig& base, const DatasetOptions& options);

}  // namespace hovs::scenes
