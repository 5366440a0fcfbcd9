// The article's six-view remap table (exact model of the reference unit, `PresetLayout("article")`), built once
// per benchmark program: the expansion and live benchmarks measure the same table. Also the panorama preset's
// table (one 360-degree cylindrical view whose rows near the rim minify: it samples the frame's pyramid), and the
// binocular preset's rig mapping.
#pragma once

#include "tests/core/test_rigs.h"
#include "unwrap/layout.h"
#include "unwrap/remap_table.h"
#include "unwrap/rig_mapping.h"

namespace hovs::test {

inline const unwrap::RemapTable& ArticleTable() {
  static const unwrap::RemapTable table =
      unwrap::BuildRemapTable(AnyModel::Exact(AlignedRig()), unwrap::PresetLayout("article"), {});
  return table;
}

inline const unwrap::RemapTable& PanoramaTable() {
  static const unwrap::RemapTable table =
      unwrap::BuildRemapTable(AnyModel::Exact(AlignedRig()), unwrap::PresetLayout("panorama"), {});
  return table;
}

// The binocular preset (the article's 3 + 3 views) over two reference units.
inline const unwrap::RigMapping& BinocularMapping() {
  static const unwrap::RigMapping mapping = unwrap::BuildRigMapping(
      {{"left", AnyModel::Exact(AlignedRig()), Rigid3d(), true},
       {"right", AnyModel::Exact(AlignedRig()), Rigid3d(Eigen::Quaterniond::Identity(), Vec3d(-0.64, 0, 0)), true}},
      unwrap::PresetLayout("binocular"), {});
  return mapping;
}

}  // namespace hovs::test
