// Several units in one pipeline: a rig layout's views (ViewSpec::unit names each view's unit), each expanded from
// its own unit's frame, in one parallel pass over all the frames (the article's binocular case: two frames to
// 3 + 3 views). One table per unit holds that unit's views; the mapping keeps the layout's order of views and is
// saved as one file (a header naming the units, then each unit's table as a mapping file's bytes, a checksum).
//
// A panorama of the whole rig (`unit: all` in the layout, two units): each unit expands the panorama, defined in
// the rig frame (unit 0's mirror frame) and turned into its own frame, and the two are blended per pixel. Each
// unit owns the half of the azimuths that faces away from the other (its own body hides the other's view there),
// with a linear ramp of blend_deg either side of the perpendicular to the baseline; where a unit's pixel is
// invalid the other fills in. Each unit sees from its own viewpoint, 0.64 m apart in the article's rig: near
// objects in the overlap differ by their parallax, which no weighting removes.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/any_model.h"
#include "unwrap/layout.h"
#include "unwrap/remap.h"
#include "unwrap/remap_table.h"

namespace hovs::unwrap {

struct RigUnitModel {
  std::string name;
  AnyModel model;
  Rigid3d unit_from_rig;  // the rig frame (unit 0's mirror frame) in this unit's mirror frame
  bool has_pose = true;   // false: unknown (a panorama of the whole rig is then refused)
};

// A view of the whole rig: which unit tables hold its parts, and each part's weights (per pixel, 0..255, summing
// to 255 where any part is valid).
struct RigBlend {
  std::vector<std::pair<int, int>> parts;     // (index into units, view index in that table)
  std::vector<std::vector<uint8_t>> weights;  // per part, width * height
};

struct RigMapping {
  std::vector<std::string> units;  // the units that have views, in the order their frames are given
  std::vector<RemapTable> tables;  // per entry of `units`: that unit's views
  // Per layout view: (index into units, view index in that table), or (-1, index into blends) for a view of
  // the whole rig.
  std::vector<std::pair<int, int>> order;
  std::vector<RigBlend> blends;
  std::string header;  // JSON: layout, units, versions
  int ViewCount() const { return static_cast<int>(order.size()); }
  const ViewTable& View(int k) const {  // a blend's first part: its name, size and projection are the view's
    const auto& [u, v] = order[k].first >= 0 ? order[k] : blends[order[k].second].parts[0];
    return tables[u].views[v];
  }
  int UnitOf(int k) const { return order[k].first; }  // -1: the whole rig
  std::string UnitName(int k) const { return order[k].first >= 0 ? units[order[k].first] : "all"; }
};

constexpr double kRigBlendDeg = 10;  // half-width of the blend ramp around the perpendicular to the baseline

// The unit a view names among `units` (by name, else as a 0-based index; empty: the first). Throws naming the
// view and listing the rig's units.
int ResolveUnit(const ViewSpec& view, const std::vector<RigUnitModel>& units);

// Builds every unit's table (each multithreaded). Throws naming a view whose unit the rig lacks.
RigMapping BuildRigMapping(const std::vector<RigUnitModel>& units, const Layout& layout, const RemapOptions& options,
                           const std::string& versions_json = "{}");

void SaveRigMapping(const std::filesystem::path& path, const RigMapping& mapping);  // atomic
RigMapping LoadRigMapping(const std::filesystem::path& path);  // checked as LoadRemapTable; throws naming the file
bool IsRigMappingFile(const std::filesystem::path& path);      // by its magic

class RigRemapper {
 public:
  explicit RigRemapper(const RigMapping& mapping);  // keeps a reference
  // frames[u] is unit u's frame (mapping.units' order), all in one pixel format; (*outputs)[k] gets layout view k.
  // Throws naming the unit whose frame does not match its mapping, or when the frames' formats differ.
  void Run(const std::vector<ImageView>& frames, Interpolation interpolation, std::vector<Image8>* outputs);

 private:
  const RigMapping& mapping_;
  std::vector<std::unique_ptr<Remapper>> remappers_;
  std::vector<std::vector<Image8>> parts_;  // per blend, its parts' expansions
};

}  // namespace hovs::unwrap
