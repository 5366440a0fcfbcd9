// View layouts: the virtual cameras and panoramas one unwrap produces, by name or from a YAML file.
//
// YAML (angles in degrees, sizes in pixels):
//   views:
//     - {name: front, type: perspective, width: 1200, height: 700, yaw: 0, pitch: -30, roll: 0, hfov: 65}
//     - {name: pano, type: cylindrical, width: 4096, height: 768, elevation_min: -70, elevation_max: -2,
//        azimuth_centre: 0, azimuth_span: 360}
//     - {name: sphere, type: longlat, width: 2048, height: 1024, elevation_min: -90, elevation_max: 90}
//     - {name: right_front, unit: right, yaw: 0}     # a rig's layout: the unit (name or 0-based index) whose frame
//                                                    # the view takes; angles in that unit's mirror frame
//     - {name: rig, unit: all, type: cylindrical}    # a panorama of the whole rig, in unit 0's frame: both units
//                                                    # blended (unwrap/rig_mapping.h)
// Presets:
//   article     the article's six 1200 x 700 perspective views, yaw 0, 60, ..., 300 degrees, pitch -30, hfov 65
//               (neighbours overlap by 5 degrees), the layout of its Figs 30-31
//   panorama    one cylindrical panorama, 3600 x 900, elevation -75 .. -2 degrees, azimuth centred on +x
//   longlat     one longitude-latitude panorama, 3600 x 1800, the whole sphere
//   binocular   the article's two-unit case (Fig. 30): 3 + 3 views of 1200 x 700, hfov 65, pitch -30, each unit
//               looking away from the other (unit 1 on unit 0's +x side, as in scenes/reference_stereo.yaml):
//               unit 0 at yaw 120, 180, 240 and unit 1 at yaw 300, 0, 60
// Given a model (ResolveLayout's second argument), the panorama preset takes its elevation range from the
// model's field instead (FieldOfModel: the elevations its valid pixels see, which leaves out the camera's own
// reflection where the model has an inner bound), and the article's views keep pitch -30 unless that puts them
// partly outside the field, in which case they are pitched the least amount that brings them inside it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "core/virtual_view.h"

namespace hovs::unwrap {

struct ViewSpec {
  std::string name;
  std::string unit;  // a rig layout's unit (name or 0-based index); empty: the only (or first) unit
  ViewProjection type = ViewProjection::kPerspective;
  int width = 1200, height = 700;
  double yaw_deg = 0, pitch_deg = -30, roll_deg = 0, hfov_deg = 65;  // perspective
  double elevation_min_deg = -75, elevation_max_deg = -2;            // panoramas
  double azimuth_centre_deg = 0, azimuth_span_deg = 360;
  // Panoramas and epipolar views: mirror_from_view (identity: the pole is the mirror axis). Epipolar views
  // (stereo rectification, built by depth/) use azimuth_centre/span for the angle from the baseline and
  // elevation_min/max for the angle around it (virtual_view.h).
  Eigen::Quaterniond pole = Eigen::Quaterniond::Identity();
  VirtualView<double> View() const;  // throws hovs::Error naming the view when the spec is invalid
  void Check(const std::string& where) const;
};

struct Layout {
  std::string name;
  std::vector<ViewSpec> views;
  void Check(const std::string& where) const;  // at least one view, unique names, every view valid
  bool IsRig() const;                          // some view names a unit
};

// An upper bound of the memory a run over these views takes beyond its input, in bytes: per pixel of every view
// its 8-bit RGB output (3 bytes) and its mapping (at most 8 bytes, a dense tile's coordinates; interpolated tiles
// take far less), and the float copy of the largest view that the image writer takes (12 bytes per pixel).
// Measured: one 8192 x 8192 panorama, 1.24 GB peak for `hovs unwrap` of one image; the bound says 1.54 GB.
std::size_t ViewsMemoryBytes(const std::vector<ViewSpec>& views);
// Refuses views whose ViewsMemoryBytes exceeds `available` (core's AvailableMemoryBytes; nullopt: no check), with
// an error naming the views' size and both amounts, before any mapping is built (a 2 x 32768 x 32768 layout
// spent 208 s building its mapping before it ran out of memory).
void CheckViewsMemory(const std::string& where, const std::vector<ViewSpec>& views,
                      std::optional<std::size_t> available);

// The elevations (degrees, mirror frame) a model's valid pixels see: the 0.1 and 99.9 percentiles over a grid of
// about 250,000 pixels of its domain (polynomial: the calibrated annulus; exact: the mirror outside the
// camera's reflection; unified: its annulus if it has one, else the whole image).
struct ModelField {
  double elevation_min_deg = 0, elevation_max_deg = 0;
  int pixels = 0;  // valid pixels sampled
};
ModelField FieldOfModel(const AnyModel& model);

Layout PresetLayout(const std::string& name);  // throws listing the known presets
// A preset fitted to a model's field (see above); a preset's fixed numbers when fixed_elevation.
Layout PresetLayout(const std::string& name, const AnyModel& model);
Layout LoadLayout(const std::filesystem::path& path);  // YAML, validated (file:line)
// The same from the file's text; `name` is the layout's name when the text gives none.
Layout ParseLayout(const std::string& text, const std::string& source, const std::string& name);
// A preset name or a YAML file; with a model, presets follow its field (PresetLayout(name, model)).
Layout ResolveLayout(const std::string& name_or_path, const AnyModel* model = nullptr);
std::vector<std::string> PresetNames();

}  // namespace hovs::unwrap
