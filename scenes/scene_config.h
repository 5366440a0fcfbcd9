// Scene files (YAML, validated on load): catadioptric units with their exact rigs, textured objects
// (checkerboards, ArUco boards drawn with OpenCV, planes, boxes, the ground), the sky and render options.
// Lengths in metres; angles in degrees where the key says _deg. Texture image paths are relative to the file.
// A unit's camera may carry a lens, camera.lens {f_number or aperture_diameter, focus_distance, wavelength}
// (core/lens.h, the keys of a design config's lens): its images are defocused through that aperture and their
// scale is the sensor distance s = f d / (d - f) at the focus d. Without one the camera is a pinhole of scale f.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "calib/checkerboard_detector.h"
#include "raytrace/render.h"
#include "raytrace/scene.h"

namespace hovs::scenes {

// A calibration target. Board frame: origin at the board centre, x along its width (squares_x / markers_x),
// y along its height, z out of the printed face.
struct BoardSpec {
  enum class Kind { kChecker, kAruco, kCharuco } kind = Kind::kChecker;
  int squares_x = 8, squares_y = 6;  // checker, charuco: squares (inner corners: (sx - 1) x (sy - 1))
  double square = 0.03;              // m
  int markers_x = 5, markers_y = 5;  // aruco grid
  double marker_length = 0.2, marker_separation = 0.04;  // aruco; charuco: marker_length (inside a square)
  std::string dictionary = "DICT_6X6_250";
  double margin = 0.02;  // white border around the pattern, m

  double Width() const;  // printed pattern plus margins
  double Height() const;
  // Corners with ids, in the board frame (z = 0): checker inner corners (id = j * (sx - 1) + i, i along x),
  // ArUco marker corners (id = 4 * marker id + k, k in OpenCV's corner order), or ChArUco inner corners (OpenCV's
  // ids, calib::CharucoSpec).
  std::vector<std::pair<int, Vec2d>> Corners() const;
  calib::CharucoSpec Charuco() const;  // kind kCharuco
};

struct BoardInstance {
  std::string name;
  int object_id = 0;
  int rect_index = 0;  // in SceneDescription::rects
  BoardSpec spec;
  Rigid3d world_from_board;
};

struct SceneConfig {
  std::string name = "scene";
  std::string source, text;
  raytrace::SceneDescription description;
  std::vector<BoardInstance> boards;
  raytrace::RenderOptions render;
};

SceneConfig ParseSceneConfig(const std::string& yaml_text, const std::string& source,
                             const std::filesystem::path& base_dir);
SceneConfig LoadSceneConfig(const std::filesystem::path& path);

// Whether units stand clear of a scene's objects (planes, boxes, boards, the ground), the objects traced once
// for units at any pose. Check throws when an object meets a segment spanning the unit's parts (its camera
// centre to the rim, the rim's and the mount's diameters, the camera body along its axis), or when the unit's
// camera centre is inside a box; `where` names the input (the scene file, a dataset frame).
class UnitClearance {
 public:
  explicit UnitClearance(const raytrace::SceneDescription& description);  // its units are ignored
  ~UnitClearance();
  void Check(const raytrace::CatadioptricUnit& unit, const std::string& where) const;

 private:
  std::vector<raytrace::SceneObjectInfo> objects_;
  std::unique_ptr<raytrace::RayScene> scene_;  // the objects alone; null without any
};
// Every unit of the description (ParseSceneConfig calls it on each scene file).
void CheckUnitsClearOfObjects(const raytrace::SceneDescription& description, const std::string& where);

// The same optics at 1/factor of the resolution (pixel pitch times factor): for quick runs. Throws when a
// camera's size is not divisible by factor.
void DownscaleCameras(SceneConfig* cfg, int factor);

// Moves the named unit to the front (monocular datasets render unit 0; the others stay in the scene as occluders).
void SelectUnit(SceneConfig* cfg, const std::string& name);

// The rect and texture for a board (ArUco boards are drawn with OpenCV's aruco module).
raytrace::Rect MakeBoardRect(const BoardSpec& spec, const Rigid3d& world_from_board, int object_id);
void CheckBoard(const BoardSpec& spec, const std::string& where);

// A rotation whose z axis points from `position` to `target`, x horizontal (world z up), then rolled.
Rigid3d LookAt(const Vec3d& position, const Vec3d& target, double roll_rad = 0);

// The camera placement of a unit: ideal (pinhole at F2) plus a misalignment: the camera centre displaced by
// `offset` (mirror frame) and `height_error` along -z (further from the mirror), and tilted by `tilt` (axis-angle,
// radians) about its own centre. Returns cam_from_mirror.
Rigid3d MisalignedCamFromMirror(const HyperboloidMirror<double>& mirror, const Vec3d& tilt, const Vec3d& offset,
                                double height_error);

}  // namespace hovs::scenes
