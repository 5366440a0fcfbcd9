#include "io/image_io.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/io.h"
#include "io/codecs.h"

namespace hovs::io {
namespace {
namespace fs = std::filesystem;

// The declared size of an image, before any of its pixels is allocated: within the limits, and its float
// buffer (with the decoder's own, up to as large again) within the memory left.
void CheckSize(const std::string& where, int width, int height, int channels, int bits) {
  HOVS_REQUIRE(width >= 1 && height >= 1, where, "the image declares a size of ", width, " x ", height);
  HOVS_REQUIRE(width <= kMaxImageSide && height <= kMaxImageSide && int64_t(width) * height <= kMaxImagePixels, where,
               "the image declares ", width, " x ", height, " pixels; hovs reads at most ", kMaxImageSide,
               " a side and ", kMaxImagePixels, " pixels in all");
  HOVS_REQUIRE(channels >= 1 && channels <= 4, where, "the image has ", channels, " channels (1 to 4 are read)");
  HOVS_REQUIRE(bits == 8 || bits == 16 || bits == 32, where, "unsupported sample size of ", bits, " bits");
  const size_t values = size_t(width) * height * channels;
  RequireMemory(where, "the image (" + std::to_string(width) + " x " + std::to_string(height) + ")",
                values * (sizeof(float) + bits / 8), AvailableMemoryBytes(), "the file's header may be damaged");
}

int BitsOf(const OIIO::TypeDesc& t) {
  if (t == OIIO::TypeDesc::UINT8 || t == OIIO::TypeDesc::INT8) return 8;
  if (t == OIIO::TypeDesc::UINT16 || t == OIIO::TypeDesc::INT16 || t == OIIO::TypeDesc::HALF) return 16;
  return 32;
}

std::unique_ptr<OIIO::ImageInput> OpenWithOiio(const fs::path& path) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) {
    std::string e = OIIO::geterror();
    std::replace(e.begin(), e.end(), '\n', ' ');
    throw Error(path.string(), "not a readable image" + (e.empty() ? std::string() : ": " + e));
  }
  return in;
}

std::string OiioError(OIIO::ImageInput& in) {
  std::string e = in.geterror();
  std::replace(e.begin(), e.end(), '\n', ' ');
  return e.empty() ? "the decoder failed" : e;
}

fs::path TempSibling(const fs::path& path) {
  const auto parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  return parent / ("." + path.stem().string() + ".tmp-" + std::to_string(::getpid()) + path.extension().string());
}

// Renames the written temporary into place (and forgets it for the interrupt's cleanup).
void Publish(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  UnregisterCleanup(tmp);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(path.string(), "cannot rename into place");
  }
}

}  // namespace

namespace {

enum class Codec { kPng, kJpeg, kOther };

// Which decoder reads the file: its signature decides, not its extension. Throws naming a missing file.
Codec CodecOf(const fs::path& path) {
  const std::string where = path.string();
  std::error_code ec;
  HOVS_REQUIRE(fs::is_regular_file(path, ec), where, fs::exists(path, ec) ? "is not a file" : "file not found");
  std::string head(8, '\0');
  FILE* f = std::fopen(path.c_str(), "rb");
  HOVS_REQUIRE(f != nullptr, where, "cannot open for reading");
  head.resize(std::fread(head.data(), 1, head.size(), f));
  std::fclose(f);
  return internal::IsPng(head) ? Codec::kPng : internal::IsJpeg(head) ? Codec::kJpeg : Codec::kOther;
}

// A PNG or JPEG file through libpng or libjpeg (pixels: false, the header only).
internal::Decoded Decode(const fs::path& path, Codec codec, bool pixels) {
  const std::string bytes = ReadFile(path);
  return codec == Codec::kPng ? internal::DecodePng(bytes, path.string(), pixels, CheckSize)
                              : internal::DecodeJpeg(bytes, path.string(), pixels, CheckSize);
}

}  // namespace

ImageHeader ReadImageHeader(const fs::path& path) {
  const Codec codec = CodecOf(path);
  ImageHeader h;
  if (codec != Codec::kOther) {
    const internal::Decoded d = Decode(path, codec, false);
    h.width = d.width, h.height = d.height, h.channels = d.channels, h.bits = d.bits;
    h.format = codec == Codec::kPng ? "png" : "jpeg";
    return h;
  }
  auto in = OpenWithOiio(path);
  const OIIO::ImageSpec& spec = in->spec();
  h.width = spec.width, h.height = spec.height, h.channels = spec.nchannels, h.bits = BitsOf(spec.format);
  h.format = in->format_name();
  CheckSize(path.string(), h.width, h.height, h.channels, h.bits);
  return h;
}

Image8Bits ReadImage8(const fs::path& path) {
  int w = 0, h = 0, c = 0;
  const PixelBuffer px = ReadImage(path, &w, &h, &c);
  HOVS_REQUIRE(c == 1 || c >= 3, path.string(), "unsupported channel count ", c, " (grey or RGB expected)");
  Image8Bits im;
  im.width = w, im.height = h, im.channels = c == 1 ? 1 : 3;
  im.data.resize(size_t(w) * h * im.channels);
  for (size_t k = 0; k < size_t(w) * h; ++k)
    for (int ch = 0; ch < im.channels; ++ch)
      im.data[k * im.channels + ch] = uint8_t(std::lround(std::clamp(px[k * c + ch], 0.f, 1.f) * 255));
  return im;
}

PixelBuffer ReadImage(const fs::path& path, int* width, int* height, int* channels) {
  const std::string where = path.string();
  const Codec codec = CodecOf(path);
  PixelBuffer out;
  if (codec != Codec::kOther) {
    const internal::Decoded d = Decode(path, codec, true);
    *width = d.width, *height = d.height, *channels = d.channels;
    const size_t n = size_t(d.width) * d.height * d.channels;
    out.resize(n);
    if (d.bits == 16) {
      const auto* s = reinterpret_cast<const uint16_t*>(d.samples.data());
      for (size_t k = 0; k < n; ++k) out[k] = s[k] * (1.0f / 65535.0f);
    } else {
      for (size_t k = 0; k < n; ++k) out[k] = d.samples[k] * (1.0f / 255.0f);
    }
    return out;
  }
  NoteInput(path);
  VerifyExpectedChecksum(path);
  auto in = OpenWithOiio(path);
  const OIIO::ImageSpec& spec = in->spec();
  CheckSize(where, spec.width, spec.height, spec.nchannels, BitsOf(spec.format));
  *width = spec.width, *height = spec.height, *channels = spec.nchannels;
  out.resize(size_t(spec.width) * spec.height * spec.nchannels);
  const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.data());
  HOVS_REQUIRE(ok, where, "corrupt or truncated image: ", OiioError(*in));
  in->close();
  return out;
}

void WriteImage(const fs::path& path, int width, int height, int channels, const float* values, size_t count,
                int bit_depth) {
  HOVS_REQUIRE(count == size_t(width) * height * channels, path.string(), "image buffer size mismatch");
  HOVS_REQUIRE(bit_depth == 8 || bit_depth == 16, path.string(), "bit depth must be 8 or 16 (got ", bit_depth, ")");
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const auto tmp = TempSibling(path);
  auto out = OIIO::ImageOutput::create(path.string());
  HOVS_REQUIRE(out != nullptr, path.string(), "no image writer for this extension: ", OIIO::geterror());
  OIIO::ImageSpec spec(width, height, channels, bit_depth == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8);
  spec.attribute("Software", "hovs");
  // zlib level 3 instead of libpng's 6: half the time for a 3 % larger file (BM_WritePng).
  spec.attribute("png:compressionLevel", 3);
  RegisterForCleanup(tmp);
  const bool ok = out->open(tmp.string(), spec) && out->write_image(OIIO::TypeDesc::FLOAT, values) && out->close();
  if (!ok) {
    std::error_code ec;
    fs::remove(tmp, ec);
    UnregisterCleanup(tmp);
    throw Error(path.string(), "cannot write image: " + out->geterror());
  }
  Publish(tmp, path);
}

const std::vector<float>& ExrChannels::at(const std::string& name) const {
  const auto it = channels.find(name);
  HOVS_REQUIRE(it != channels.end(), source.empty() ? std::string("ground truth") : source, "no channel '", name,
               "' (a hovs ground-truth EXR has Z, P.X/Y/Z, N.X/Y/Z, id, mask, M.X/Y/Z)");
  return it->second;
}

ExrChannels ReadExr(const fs::path& path) {
  const std::string where = path.string();
  std::error_code ec;
  HOVS_REQUIRE(fs::is_regular_file(path, ec), where, fs::exists(path, ec) ? "is not a file" : "file not found");
  NoteInput(path);
  VerifyExpectedChecksum(path);
  auto in = OpenWithOiio(path);
  const OIIO::ImageSpec& spec = in->spec();
  HOVS_REQUIRE(spec.nchannels >= 1 && spec.nchannels <= 64, where, "has ", spec.nchannels, " channels (1 to 64 read)");
  HOVS_REQUIRE(spec.width >= 1 && spec.height >= 1 && spec.width <= kMaxImageSide && spec.height <= kMaxImageSide &&
                   int64_t(spec.width) * spec.height <= kMaxImagePixels,
               where, "the file declares ", spec.width, " x ", spec.height, " pixels; hovs reads at most ",
               kMaxImageSide, " a side and ", kMaxImagePixels, " pixels in all");
  const size_t values = size_t(spec.width) * spec.height * spec.nchannels;
  RequireMemory(where, "the OpenEXR image", 2 * values * sizeof(float), AvailableMemoryBytes(),
                "the file's header may be damaged");
  ExrChannels out;
  out.width = spec.width, out.height = spec.height, out.source = where;
  // The interleaved file (290 MB for a full-size frame's 12 channels) in huge pages, as a frame's buffers.
  PixelBuffer data(values);
  const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, data.data());
  HOVS_REQUIRE(ok, where, "corrupt or truncated OpenEXR: ", OiioError(*in));
  for (int c = 0; c < spec.nchannels; ++c) {
    std::vector<float>& ch = out.channels[spec.channelnames[c]];
    ch.resize(size_t(spec.width) * spec.height);
    for (size_t i = 0; i < ch.size(); ++i) ch[i] = data[i * spec.nchannels + c];
  }
  for (const auto& p : spec.extra_attribs)
    if (p.type() == OIIO::TypeDesc::STRING) out.attributes[p.name().string()] = p.get_string();
  in->close();
  return out;
}

void WriteExr(const fs::path& path, int width, int height, const std::vector<std::string>& names, const float* values,
              const std::vector<std::pair<std::string, std::string>>& metadata, const std::string& compression) {
  HOVS_REQUIRE(compression == "none" || compression == "rle" || compression == "zips" || compression == "zip" ||
                   compression == "piz",
               path.string(), "unknown OpenEXR compression '", compression, "' (none, rle, zips, zip, piz)");
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const auto tmp = TempSibling(path);
  auto out = OIIO::ImageOutput::create("exr");
  HOVS_REQUIRE(out != nullptr, path.string(), "no OpenEXR writer: ", OIIO::geterror());
  OIIO::ImageSpec spec(width, height, static_cast<int>(names.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames = names;
  // PIZ by default: lossless like zip, 17 % smaller and 25 % faster on the ground-truth channels
  // (BM_WriteGroundTruthExr).
  spec.attribute("compression", compression);
  spec.attribute("Software", "hovs");
  // No write time (OpenImageIO stamps the EXR's capDate otherwise): the same render is the same file, so that
  // shards merged equal one process's set byte for byte. The frame's own metadata says what it is.
  spec.attribute("DateTime", "");
  for (const auto& [k, v] : metadata) spec.attribute(k, v);
  RegisterForCleanup(tmp);
  const bool ok = out->open(tmp.string(), spec) && out->write_image(OIIO::TypeDesc::FLOAT, values) && out->close();
  if (!ok) {
    std::error_code ec;
    fs::remove(tmp, ec);
    UnregisterCleanup(tmp);
    throw Error(path.string(), "cannot write OpenEXR: " + out->geterror());
  }
  Publish(tmp, path);
}

std::map<std::string, std::string> IoVersions() {
  std::map<std::string, std::string> v;
  const int oiio = OIIO::openimageio_version();  // 10000 * major + 100 * minor + patch
  v["openimageio"] =
      std::to_string(oiio / 10000) + "." + std::to_string(oiio / 100 % 100) + "." + std::to_string(oiio % 100);
  // "openexr:OpenEXR 3.1.5;tiff:LIBTIFF Version 4.5.0;...": the entry's last word.
  std::string list;
  if (OIIO::getattribute("library_list", list)) {
    const size_t at = list.find("openexr:");
    if (at != std::string::npos) {
      const std::string entry = list.substr(at, list.find(';', at) - at);
      v["openexr"] = entry.substr(entry.find_last_of(' ') + 1);
    }
  }
  v["libpng"] = internal::PngVersion();
  v["libjpeg"] = internal::JpegVersion();
  return v;
}

}  // namespace hovs::io
