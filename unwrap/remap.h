// The fast remap: a frame in, every view of a remap table out.
//
// Input: 8-bit grey, 8-bit RGB (interleaved) or a raw 8-bit RGGB Bayer mosaic (the GX2750's BayerRG8). Bayer
// input is demosaiced inside the remap: each output pixel interpolates the R, G and B sample grids of the
// mosaic at its source position (bilinear on each colour's own grid; G averages its two grids), so a camera's
// raw frame goes straight to RGB views. Output: grey for grey input, RGB otherwise.
//
// Interpolation: bilinear (default; 6-bit fixed-point weights, positions rounded to 1/64 px; AVX2 when present),
// nearest, or bicubic (Keys, a = -0.5). Tiles that minify sample a 2 x 2 box pyramid of the frame built once per frame,
// only to the levels the table needs (for Bayer input, level 1 is the mosaic's own 2 x 2 cells as RGB pixels). Interior
// tiles (all taps inside the image) run without bounds checks; others clamp to the border. Work is spread over threads
// by tile rows of all views at once (TBB).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "unwrap/remap_table.h"

namespace hovs::unwrap {

enum class PixelFormat { kGray8, kRgb8, kBayerRggb8 };
enum class Interpolation { kNearest, kBilinear, kBicubic };

const char* ToString(PixelFormat f);
const char* ToString(Interpolation i);
PixelFormat ParsePixelFormat(const std::string& s);      // gray, rgb, bayer_rggb; throws
Interpolation ParseInterpolation(const std::string& s);  // nearest, bilinear, bicubic; throws

struct ImageView {
  const uint8_t* data = nullptr;
  int width = 0, height = 0;
  size_t stride = 0;  // bytes per row
  PixelFormat format = PixelFormat::kRgb8;
};

struct Image8 {
  int width = 0, height = 0, channels = 0;
  std::vector<uint8_t> data;  // rows of width * channels bytes
  ImageView View(PixelFormat f) const { return {data.data(), width, height, size_t(width) * channels, f}; }
};

// An image file as 8-bit grey (one channel) or RGB (three or more channels: alpha dropped); errors as
// io::ReadImage (naming the file).
Image8 LoadImage8(const std::filesystem::path& path);

// One level of the 2 x 2 box pyramid: out becomes ceil(w / 2) x ceil(h / 2) with, per channel,
// out(i, j) = (in(2i, 2j) + in(2i + 1, 2j) + in(2i, 2j + 1) + in(2i + 1, 2j + 1) + 2) >> 2, the last column or row
// of an odd-sized image counted twice. A Bayer mosaic (RGGB; even width and height) becomes RGB: each 2 x 2
// cell's R, the mean of its two G (rounded half up), its B. Grey stays grey. Threads over rows (TBB).
void DownsampleHalf(const ImageView& in, Image8* out);

class Remapper;

// One remapper's share of a multi-frame pass: its frame, and where each of its table's views goes.
struct RemapJob {
  Remapper* remapper = nullptr;
  ImageView src;
  std::vector<Image8*> outputs;  // one per view of the remapper's table
};
// Several remappers, each with its own frame (the units of a rig), in one parallel pass over the tile rows of all
// their views, so that the threads share the work of every frame. Throws as Remapper::Run.
void RunRemappers(const std::vector<RemapJob>& jobs, Interpolation interpolation);

class Remapper {
 public:
  explicit Remapper(const RemapTable& table);  // keeps a reference: the table must outlive the remapper

  // Remaps src into every view; (*outputs)[i] is resized to view i. Throws hovs::Error when the frame's size
  // does not match the table's source size or the frame is malformed.
  void Run(const ImageView& src, Interpolation interpolation, std::vector<Image8>* outputs);
  // One view only (e.g. an interactive viewer updating the view it changed).
  void RunView(const ImageView& src, Interpolation interpolation, int view, Image8* output);

  double last_pyramid_ms() const { return pyramid_ms_; }

 private:
  friend void RunRemappers(const std::vector<RemapJob>& jobs, Interpolation interpolation);
  void Prepare(const ImageView& src);
  void RemapRows(const ImageView& src, Interpolation interpolation, int view, int tile_row, Image8* out) const;

  const RemapTable& table_;
  std::vector<Image8> pyramid_;  // levels 1..L-1 (grey or RGB)
  double pyramid_ms_ = 0;
};

}  // namespace hovs::unwrap
