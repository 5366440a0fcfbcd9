// Remap tables: for every pixel of every view of a layout, where to sample the catadioptric image.
//
// Representation (compact, built once, saved to a mapping file):
//   Each view is cut into tiles of T x T output pixels, T per view (8, 16, 32 or 64; see RemapOptions::tile for
//   how it is chosen). A tile is
//     empty   no pixel sees the mirror (outside the rim, the camera's own reflection, outside the image):
//             its pixels are written as 0;
//     interp  every pixel is valid and the source coordinates are biquadratic in the output pixel within
//             max_interp_error (1/64 px by default, checked at every pixel against the exact model):
//             only 3 x 3 node coordinates are stored and the remap evaluates the quadratic per row;
//     dense   otherwise (rim and reflection boundaries, strongly curved regions): per-pixel coordinates,
//             with a sentinel for invalid pixels.
//   Dense coordinates are fixed point 16.16 source pixels (conventions.h: pixel centres at integers). A tile that
//   minifies (more than 2 source pixels per output pixel) samples level L of a 2 x 2 box pyramid of the source
//   (antialiasing); its coordinates are stored at that level: x_L = (x + 0.5) / 2^L - 0.5.
//
// Mapping file (binary, little-endian):
//   "HOVSMAP\0", uint32 format version, uint32 header length, header (JSON: model with its parameters, the
//   layout, options, source image size, versions), per view: uint32 tiles_x, tiles_y, tile size, uint32 tile
//   count, tiles, uint64 dense count, dense coordinates; then a uint64 FNV-1a checksum of everything before it.
//   Version 2 lets the views' tile sizes differ (version 1, which had one tile size for every view, is still
//   read). Loading verifies magic, version and checksum, and fails with the reason otherwise.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "unwrap/layout.h"

namespace hovs::unwrap {

struct RemapOptions {
  // Output tile size: 8, 16, 32 or 64 for every view, or 0 (automatic, the default): a view gets 64 x 64 tiles
  // when at that size every tile that sees the mirror is interp at pyramid level 0 and inside the image (no
  // per-pixel coordinates, no minification, no clamped taps), else 32 x 32. Larger tiles carry less per-tile work (row
  // polynomials, the source patch and its overlap with the neighbours' patches): the article's six views, all interp at
  // 64, remap about 10 % faster than at 32; views that cross the rim or the camera's reflection, or minify, keep 32,
  // where a 64 tile would need four times the per-pixel coordinates or pick one pyramid level for a larger area.
  int tile = 0;
  double max_interp_error = 1.0 / 64;  // px, level-0 source pixels
  bool antialias = true;               // minifying tiles sample a box-filtered pyramid level
  int max_level = 4;
  void Check(const std::string& where) const;
};

enum class TileKind : uint8_t { kEmpty = 0, kInterp = 1, kDense = 2 };

struct Tile {
  TileKind kind = TileKind::kEmpty;
  uint8_t level = 0;   // pyramid level sampled
  uint8_t inside = 0;  // 1: every coordinate lies at least 2 px inside the level's image (no clamping)
  uint8_t reserved = 0;
  uint32_t dense_index = 0;  // dense tiles: first pixel in ViewTable::dense (T * T pixels, row-major)
  // Interp tiles: source coordinates (at `level`) of the 3 x 3 nodes at tile pixels (0, T/2, T) x (0, T/2, T),
  // row-major (node k = 3 * row + column). Coordinates are biquadratic in the tile pixel.
  float x[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  float y[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
};
static_assert(sizeof(Tile) == 80, "Tile layout is part of the mapping file format");

constexpr int32_t kInvalidCoordinate = INT32_MIN;
// The largest source image a remap table maps: its 16.16 fixed-point coordinates hold up to 32767 px.
constexpr int kMaxSourceSide = 30000;

// Row j (0 <= j < T) of an interp tile: the coordinates of its pixels i = 0..T-1 are quadratic in i,
//   x_i = int32(bx + i * (c1x + i * c2x)) - 65536   (16.16 fixed point; float arithmetic in this order),
// biquadratic (Lagrange) through the tile's 3 x 3 nodes. The scalar and the AVX2 kernels and DecodeView all
// evaluate exactly this, so decoded maps are bit-exact with what the remap samples. Valid above -1 px.
struct RowPoly {
  float bx, c1x, c2x, by, c1y, c2y;
  int32_t X(int i) const {
    const float fi = float(i);
    return static_cast<int32_t>(bx + fi * (c1x + fi * c2x)) - 65536;
  }
  int32_t Y(int i) const {
    const float fi = float(i);
    return static_cast<int32_t>(by + fi * (c1y + fi * c2y)) - 65536;
  }
};
inline RowPoly InterpRowPoly(const Tile& t, int T, int j) {
  const float s = float(j) / float(T);
  const float l0 = 2 * (s - 0.5f) * (s - 1), l1 = -4 * s * (s - 1), l2 = 2 * s * (s - 0.5f);
  float ax[3], ay[3];
  for (int k = 0; k < 3; ++k) {
    ax[k] = l0 * t.x[k] + l1 * t.x[3 + k] + l2 * t.x[6 + k];
    ay[k] = l0 * t.y[k] + l1 * t.y[3 + k] + l2 * t.y[6 + k];
  }
  const float inv = 1.0f / float(T), inv2 = inv * inv;
  return {(ax[0] + 1) * 65536.f,
          (-3 * ax[0] + 4 * ax[1] - ax[2]) * inv * 65536.f,
          (2 * ax[0] - 4 * ax[1] + 2 * ax[2]) * inv2 * 65536.f,
          (ay[0] + 1) * 65536.f,
          (-3 * ay[0] + 4 * ay[1] - ay[2]) * inv * 65536.f,
          (2 * ay[0] - 4 * ay[1] + 2 * ay[2]) * inv2 * 65536.f};
}
// InterpRowPoly of rows j0 .. j0 + kRows - 1, structure of arrays: written as a loop over the rows so that a
// vectorising build evaluates them together (the same operations per row, so the same bits where the file is
// compiled without fused multiply-adds, as the kernels are).
template <int kRows>
struct RowPolys {
  alignas(64) float bx[kRows], c1x[kRows], c2x[kRows], by[kRows], c1y[kRows], c2y[kRows];
  RowPoly Row(int k) const { return {bx[k], c1x[k], c2x[k], by[k], c1y[k], c2y[k]}; }
};
template <int kRows>
__attribute__((always_inline)) inline void InterpRowPolys(const Tile& t, int T, int j0, RowPolys<kRows>* out) {
  for (int k = 0; k < kRows; ++k) {
    const RowPoly p = InterpRowPoly(t, T, j0 + k);
    out->bx[k] = p.bx, out->c1x[k] = p.c1x, out->c2x[k] = p.c2x, out->by[k] = p.by, out->c1y[k] = p.c1y,
    out->c2y[k] = p.c2y;
  }
}
inline void InterpRow(const Tile& t, int T, int j, int32_t* xs, int32_t* ys) {
  const RowPoly p = InterpRowPoly(t, T, j);
  for (int i = 0; i < T; ++i) xs[i] = p.X(i), ys[i] = p.Y(i);
}

struct ViewTable {
  ViewSpec spec;
  VirtualView<double> view;
  int tile = 32;  // T: this view's tile size
  int tiles_x = 0, tiles_y = 0;
  std::vector<Tile> tiles;
  std::vector<int32_t> dense;  // x, y pairs (16.16 at the tile's level); kInvalidCoordinate for invalid pixels
  // Statistics of the build.
  int64_t valid_pixels = 0;
  int interp_tiles = 0, dense_tiles = 0, empty_tiles = 0;
  double max_interp_error = 0;  // px, over interp tiles
  int max_level = 0;
};

struct RemapTable {
  int source_width = 0, source_height = 0;
  int levels = 1;      // pyramid levels any tile samples (1: no pyramid)
  std::string header;  // JSON: model, layout, options, versions (written into the mapping file)
  std::vector<ViewTable> views;
  double build_seconds = 0;

  // Per-pixel source coordinates of a view at level 0 as the table encodes them (-1 for invalid pixels):
  // what the fast remap samples, for comparisons (cv::remap with the same maps) and tests.
  void DecodeView(int view, std::vector<float>* map_x, std::vector<float>* map_y) const;
};

// Exact per-pixel source coordinates of a view (-1 where invalid), computed from the model directly.
void ExactMaps(const AnyModel& model, const VirtualView<double>& view, std::vector<float>* map_x,
               std::vector<float>* map_y);

// Builds the tables of every view of the layout (multithreaded). `versions` is recorded in the header.
RemapTable BuildRemapTable(const AnyModel& model, const Layout& layout, const RemapOptions& options,
                           const std::string& versions_json = "{}");

void SaveRemapTable(const std::filesystem::path& path, const RemapTable& table);  // atomic
std::string SerializeRemapTable(const RemapTable& table);  // the file's bytes (ParseRemapTable reads them)
uint64_t MappingChecksum(const char* data, size_t size);   // the mapping files' checksum (FNV-1a, 64 bits)
// Verified (magic, version, checksum) and checked field by field against its header, so that a damaged or edited
// file, even one given a valid checksum again, cannot make the remap read outside the frame. Throws hovs::Error.
RemapTable LoadRemapTable(const std::filesystem::path& path);
// The same from the file's bytes (`where` names it in errors).
RemapTable ParseRemapTable(const std::string& bytes, const std::string& where);

// The header of a mapping file as JSON text (for reports) without loading the tables.
std::string MappingFileHeader(const std::filesystem::path& path);

}  // namespace hovs::unwrap
