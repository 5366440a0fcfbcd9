// Mapping files (.hmap): the bytes are given a valid checksum (FNV-1a guards against damage, not edits), so the
// fuzzer reaches every field; a table that loads is remapped from a frame of its source size (grey, RGB and
// Bayer), where AddressSanitizer would catch a read outside the frame.
#include <vector>

#include "tests/fuzz/fuzz_common.h"
#include "unwrap/remap.h"
#include "unwrap/remap_table.h"

namespace {

void Run(const std::string& input) {
  std::string bytes = input;
  uint64_t h = 1469598103934665603ull;
  for (const char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  bytes.append(reinterpret_cast<const char*>(&h), 8);
  const hovs::unwrap::RemapTable table = hovs::unwrap::ParseRemapTable(bytes, "fuzz.hmap");
  int64_t out = 0;
  for (const auto& v : table.views) out += int64_t(v.view.width) * v.view.height;
  const int w = table.source_width, h2 = table.source_height;
  if (int64_t(w) * h2 > 4096 * 4096 || out > 8 * 1024 * 1024) return;  // valid but too large to remap per input
  std::vector<uint8_t> frame(size_t(w + w % 2) * (h2 + h2 % 2) * 3, 77);
  hovs::unwrap::Remapper remapper(table);
  std::vector<hovs::unwrap::Image8> views;
  using hovs::unwrap::PixelFormat;
  remapper.Run({frame.data(), w, h2, size_t(w) * 3, PixelFormat::kRgb8}, hovs::unwrap::Interpolation::kBilinear,
               &views);
  remapper.Run({frame.data(), w, h2, size_t(w), PixelFormat::kGray8}, hovs::unwrap::Interpolation::kBicubic, &views);
  if (w % 2 == 0 && h2 % 2 == 0)
    remapper.Run({frame.data(), w, h2, size_t(w), PixelFormat::kBayerRggb8}, hovs::unwrap::Interpolation::kBilinear,
                 &views);
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
