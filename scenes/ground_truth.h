// Ground truth of rendered frames: exact image positions of board corners through the core's projection
// (closed form for single-viewpoint rigs, the law-of-reflection solve otherwise) with their visibility, and the
// JSON forms of rigs and poses shared by sidecars and dataset manifests.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "raytrace/scene.h"
#include "scenes/scene_config.h"

namespace hovs::scenes {

struct CornerTruth {
  int id = 0;
  Vec2d board_xy = Vec2d::Zero();  // board frame, m
  Vec3d world = Vec3d::Zero();
  Vec2d pixel = Vec2d::Zero();  // valid when status == "visible"
  Vec3d mirror_point = Vec3d::Zero();
  std::string status;  // visible | facing_away | occluded | <core projection status>
};

// Projects every corner of the board into the unit's image and classifies its visibility.
std::vector<CornerTruth> BoardCornerTruth(const raytrace::RayScene& scene, const BoardInstance& board, int unit);

nlohmann::json PoseToJson(const Rigid3d& pose);  // {"q": [w, x, y, z], "t": [x, y, z]}
Rigid3d PoseFromJson(const nlohmann::json& j, const std::string& where);
nlohmann::json UnitToJson(const raytrace::CatadioptricUnit& unit);
raytrace::CatadioptricUnit UnitFromJson(const nlohmann::json& j, const std::string& where);
nlohmann::json BoardToJson(const BoardInstance& board);

// The per-frame sidecar: rig, board poses, corner truth, channel documentation.
nlohmann::json FrameSidecar(const SceneConfig& config, const raytrace::RayScene& scene, int unit);

// The visible corners of the first board of a sidecar file written from FrameSidecar (truth/*.json): id, board
// position and exact pixel, and the world point and the reflection point on the mirror where the file has them. Throws
// hovs::Error naming the file when it is not such a sidecar.
std::vector<CornerTruth> VisibleSidecarCorners(const std::filesystem::path& sidecar);
// The same from a sidecar already parsed (`where` names it).
std::vector<CornerTruth> VisibleSidecarCorners(const nlohmann::json& sidecar, const std::string& where);

// Each view's unit pose (world_from_mirror) in a rendered dataset, read from its ground-truth sidecar, keyed by the
// view's image path (ManifestPath, lexically normal); views without ground truth are absent. Throws naming a
// sidecar that is not one.
std::map<std::filesystem::path, Rigid3d> ViewPosesByImage(const std::filesystem::path& manifest);

}  // namespace hovs::scenes
