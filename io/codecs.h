// PNG and JPEG decoding with libpng and libjpeg, every message of theirs turned into the error (image_io.cc).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hovs::io::internal {

// A decoded image: 8-bit samples (bits == 8) or native-endian 16-bit ones (bits == 16), interleaved.
struct Decoded {
  int width = 0, height = 0, channels = 0, bits = 8;
  std::vector<uint8_t> samples;
};

// The size check run between the header and the pixels; throws to refuse (the decoder cleans up).
using SizeCheck = void (*)(const std::string& where, int width, int height, int channels, int bits);

bool IsPng(const std::string& bytes);
bool IsJpeg(const std::string& bytes);

// Decode `bytes` (the whole file). With pixels = false only the header fields are filled. Throw hovs::Error(where)
// with the decoder's message on any error or warning that means damaged data.
Decoded DecodePng(const std::string& bytes, const std::string& where, bool pixels, SizeCheck check);
Decoded DecodeJpeg(const std::string& bytes, const std::string& where, bool pixels, SizeCheck check);

std::string PngVersion();
std::string JpegVersion();

}  // namespace hovs::io::internal
