// Image and ground-truth files: reading with the declared size checked before anything is allocated and every
// decoder complaint (a truncated JPEG or PNG, a bad checksum) an error naming the file, and atomic writing.
//
// PNG and JPEG are decoded here with libpng and libjpeg directly (their messages become the error, nothing is
// printed); other formats (OpenEXR, TIFF, BMP, PGM/PPM, ...) through OpenImageIO. Values are floats in [0, 1]
// (8-bit v / 255, 16-bit v / 65535) or as stored (float formats).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/large_pages.h"

namespace hovs::io {

// A float buffer whose resize() leaves new elements uninitialised, in huge pages when large
// (core/large_pages.h): a full-size frame (72 MB as float RGB) is read or rendered without zeroing it first.
using PixelBuffer = std::vector<float, LargePageAllocator<float, /*UninitialisedConstruct=*/true>>;

// The largest image hovs reads: 65535 pixels a side and 2^28 pixels (a 16384 x 16384 frame) in all, and no more
// than the memory left (AvailableMemoryBytes). A file declaring more is refused before its pixels are read.
inline constexpr int kMaxImageSide = 65535;
inline constexpr int64_t kMaxImagePixels = int64_t(1) << 28;

struct ImageHeader {
  int width = 0, height = 0, channels = 0;
  int bits = 8;        // per channel as stored: 8, 16 or 32 (float)
  std::string format;  // "png", "jpeg", or OpenImageIO's format name
};

// The header of an image file, checked (size within the limits above, 1 to 4 channels). Throws hovs::Error
// naming the file.
ImageHeader ReadImageHeader(const std::filesystem::path& path);

// The whole image as interleaved float channels. Throws hovs::Error naming the file: not an image, a declared size
// beyond the limits or the memory left, a truncated or corrupt file. The path is noted as an input (core/io.h).
PixelBuffer ReadImage(const std::filesystem::path& path, int* width, int* height, int* channels);

// An 8-bit image: one channel (grey) or three (RGB; a fourth, alpha, is dropped).
struct Image8Bits {
  int width = 0, height = 0, channels = 0;
  std::vector<uint8_t> data;  // interleaved, row-major
};

// ReadImage rounded to 8 bits (values clamped to [0, 1]). Throws as ReadImage, and for 2 channels.
Image8Bits ReadImage8(const std::filesystem::path& path);

// Writes a PNG (8 or 16 bits per channel; other extensions: OpenImageIO's writer for it) atomically (temporary
// file + rename).
void WriteImage(const std::filesystem::path& path, int width, int height, int channels, const float* values,
                size_t count, int bit_depth);
template <class Allocator>
void WriteImage(const std::filesystem::path& path, int width, int height, int channels,
                const std::vector<float, Allocator>& values, int bit_depth) {
  WriteImage(path, width, height, channels, values.data(), values.size(), bit_depth);
}

// Named float channels of an OpenEXR file (channel order in the file does not matter).
struct ExrChannels {
  int width = 0, height = 0;
  std::map<std::string, std::vector<float>> channels;
  std::map<std::string, std::string> attributes;  // string attributes, e.g. "hovs:unit"
  std::string source;                             // the file, for errors
  // The channel, or an error naming the file and the channel.
  const std::vector<float>& at(const std::string& name) const;
};
ExrChannels ReadExr(const std::filesystem::path& path);

// Writes interleaved float channels as OpenEXR atomically, with `metadata` as string attributes and OpenEXR's
// `compression` (none, rle, zips, zip, piz: the lossless ones).
void WriteExr(const std::filesystem::path& path, int width, int height, const std::vector<std::string>& names,
              const float* values, const std::vector<std::pair<std::string, std::string>>& metadata,
              const std::string& compression = "piz");

// "openimageio" and "openexr" (the libraries loaded), "libpng", "libjpeg".
std::map<std::string, std::string> IoVersions();

}  // namespace hovs::io
