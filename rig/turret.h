// The variable-scale unit as a machine (the article's section 3.1, item 2, Fig. 6): a turret disc carrying
// hyperboloid mirrors, each on its own mounting plate with a fiducial label (ArUco markers on the plate's
// underside, seen by the camera directly, outside the mirror image), a push rod that sets the plate's height, two
// lateral axes and two tilts that align the mirror axis with the camera's optical axis, and the lens focus.
//
// The machine file (YAML; lengths in metres, the turret and tilt axes and slot angles in degrees):
//   name, camera {focal_length, pixel_pitch, width, height, lens_aperture}, lens {f_number or aperture_diameter,
//     wavelength} (core/lens.h; the focus axis sets its focus; without it the camera is a pinhole),
//   surroundings: a scene file whose objects and sky are rendered around the unit; its first unit's pose places
//     the nominal viewpoint of the first mirror (the camera stays there for every mirror),
//   turret {radius}: distance of the mirror axes from the turret's axis (which lies along -x of the camera),
//   mirrors [{id, a, b, rim_diameter, slot_deg}],
//   label {dictionary, marker_length, margin, centres [[x, y], ...]}: marker i (id i) centred at (x, y) in the
//     plate frame, 0.3 mm below the rim plane, facing the camera,
//   axes {turret, rod, x, y, tilt_x, tilt_y, focus}: each {min, max, step, time_constant, backlash, noise},
//   render {downscale, samples, board_samples, seed}: samples per pixel of the loop's images and of the
//     calibration boards' images.
//
// Pose of a mirror: its deviation from the nominal placement for its slot (camera pinhole at the mirror's second
// focus, axes aligned), in the nominal mirror frame: the plate centre (on the axis, in the rim plane) displaced
// by `offset`, the plate turned by the rotation vector `rotation` about that centre. The truth follows from the
// axes' true positions and each mirror's seating errors on the turret; the label measures it from one image.
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/catadioptric.h"
#include "core/lens.h"
#include "raytrace/render.h"
#include "rig/actuators.h"

namespace hovs::scenes {
struct SceneConfig;
}

namespace hovs::rig {

struct TurretMirror {
  std::string id;
  HyperboloidMirror<double> mirror;
  double slot = 0;  // rad, turret angle that puts it over the camera
  // Plate height (rim plane above the pinhole) with the pinhole at the second focus: the rod's target.
  double PlateHeight() const { return mirror.RimZ() + 2 * mirror.c(); }
};

struct LabelSpec {
  std::string dictionary = "DICT_4X4_50";
  double marker_length = 0.006, margin = 0.001;  // m
  std::vector<Vec2d> centres;                    // plate frame, m; marker i has id i
  double depth = 0.0003;                         // below the rim plane (towards the camera), m
  // Corner k (OpenCV's order: top-left, top-right, bottom-right, bottom-left as printed) of marker i, in the
  // plate frame (origin at the plate centre, axes of the mirror frame).
  Vec3d Corner(int marker, int k) const;
};

struct TurretSpec {
  std::string name, source, text;
  PinholeCamera<double> camera;
  double lens_aperture = 0.020;  // diameter of the lens face (occluder), m
  double pixel_pitch = 4.54e-6;  // m
  std::optional<ThinLens> lens;  // the thin lens of the defocus (none: a pinhole); its focus: the focus axis
  double LensRadius() const { return lens ? lens->ApertureRadius() : 0.0; }
  double turret_radius = 0.09;
  std::vector<TurretMirror> mirrors;
  LabelSpec label;
  std::array<AxisSpec, kAxisCount> axes;
  std::shared_ptr<const scenes::SceneConfig> surroundings;
  Rigid3d world_from_cam;  // the camera's fixed place
  int downscale = 2, samples = 4;
  int board_samples = 16;  // calibration boards: corners a calibration can trust need less sampling noise
  uint64_t seed = 1;

  // The camera of the rendered images: `downscale` times fewer pixels, the same optics.
  PinholeCamera<double> ImageCamera() const;
  int MirrorIndex(const std::string& id) const;  // throws naming the id and the known ones
  // The axis positions that place mirror k exactly at its nominal pose when it has no seating error.
  std::array<double, kAxisCount> NominalAxes(int k, double focus) const;
};

TurretSpec ParseTurretSpec(const std::string& yaml_text, const std::string& source, const std::filesystem::path& base);

// What calibrations made on a machine depend on: the camera, the turret and its mirrors (ids, a, b, rim, slots) and
// the label, as JSON (a rig folder records its checksum: files made on another machine are refused).
nlohmann::json MachineGeometryJson(const TurretSpec& spec);
TurretSpec LoadTurretSpec(const std::filesystem::path& path);

struct MirrorPose {
  Vec3d offset = Vec3d::Zero();    // m: x, y lateral, z height (+ away from the camera)
  Vec3d rotation = Vec3d::Zero();  // rad: rotation vector about the plate centre (x, y tilt, z yaw)
  double LateralM() const { return offset.head<2>().norm(); }
  // Angle between the mirror axis and the camera's optical axis.
  double TiltRad() const;
};

// The pose of mirror k over the camera from the axes' true positions and its seating error on the turret.
MirrorPose PoseFromAxes(const TurretSpec& spec, int k, const std::array<double, kAxisCount>& axes,
                        const MirrorPose& seat);
// cam_from_mirror of mirror k at `pose`.
Rigid3d CamFromMirror(const TurretSpec& spec, int k, const MirrorPose& pose);
// The pose whose cam_from_mirror is given (the inverse of CamFromMirror).
MirrorPose PoseFromCamFromMirror(const TurretSpec& spec, int k, const Rigid3d& cam_from_mirror);
// The exact rig of mirror k at `pose` (full resolution).
CatadioptricCamera<double> RigAt(const TurretSpec& spec, int k, const MirrorPose& pose);

// One image of the unit: 8-bit grey, spec.downscale times smaller than the camera.
struct TurretImage {
  int width = 0, height = 0;
  std::vector<uint8_t> grey;
  double render_seconds = 0;
};
// The scene of mirror k at `pose`: the surroundings, the unit (at spec.ImageCamera()'s resolution) and its label,
// with the machine's render settings and the lens focused at focus_distance.
scenes::SceneConfig TurretSceneConfig(const TurretSpec& spec, int k, const MirrorPose& pose, double focus_distance,
                                      uint64_t seed, bool label_covered = false);
// Renders mirror k at `pose` with the lens focused at focus_distance; label_covered hides the label (a fault).
TurretImage RenderTurret(const TurretSpec& spec, int k, const MirrorPose& pose, double focus_distance, uint64_t seed,
                         bool label_covered = false);

}  // namespace hovs::rig
