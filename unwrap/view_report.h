// What a remap table's views are and how well they are filled, as records: each view's geometry (K and pose for a
// perspective view, the angular ranges of a panorama) and tiles, and the PSNR of an unwrapped view against a
// reference image of the same view (e.g. a pinhole render of the scene).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "unwrap/remap.h"
#include "unwrap/remap_table.h"

namespace hovs::unwrap {

nlohmann::json ViewJson(const ViewTable& view);

struct ViewPsnr {
  double psnr_db = 0;  // over the view's valid pixels (those the mapping fills); 0 without any
  double valid_fraction = 0;
};

// view_index into table.views; `view` and `reference` are RGB8 of the view's size.
ViewPsnr CompareWithReference(const RemapTable& table, int view_index, const Image8& view,
                              const std::vector<uint8_t>& reference);

}  // namespace hovs::unwrap
