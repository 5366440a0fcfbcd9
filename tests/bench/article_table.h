// The article's six-view remap table (exact model of the reference unit, `PresetLayout("article")`), built once
// per benchmark program: the expansion and live benchmarks measure the same table.
#pragma once

#include "tests/core/test_rigs.h"
#include "unwrap/layout.h"
#include "unwrap/remap_table.h"

namespace hovs::test {

inline const unwrap::RemapTable& ArticleTable() {
  static const unwrap::RemapTable table =
      unwrap::BuildRemapTable(AnyModel::Exact(AlignedRig()), unwrap::PresetLayout("article"), {});
  return table;
}

}  // namespace hovs::test
