// Several units in one pipeline: a rig layout's views (ViewSpec::unit names each view's unit), each expanded from
// its own unit's frame, in one parallel pass over all the frames (the article's binocular case: two frames to
// 3 + 3 views). One table per unit holds that unit's views; the mapping keeps the layout's order of views and is
// saved as one file (a header naming the units, then each unit's table as a mapping file's bytes, a checksum).
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
};

struct RigMapping {
  std::vector<std::string> units;          // the units that have views, in the order their frames are given
  std::vector<RemapTable> tables;          // per entry of `units`: that unit's views
  std::vector<std::pair<int, int>> order;  // per layout view: (index into units, view index in that table)
  std::string header;                      // JSON: layout, units, versions
  int ViewCount() const { return static_cast<int>(order.size()); }
  const ViewTable& View(int k) const { return tables[order[k].first].views[order[k].second]; }
  int UnitOf(int k) const { return order[k].first; }
};

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
};

}  // namespace hovs::unwrap
