#include "io/codecs.h"

#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <jpeglib.h>
#include <jerror.h>

#include <algorithm>
#include <cstring>

#include "core/error.h"

namespace hovs::io::internal {
namespace {

// ------------------------------------------------------------------------------------------------- PNG
// libpng reports errors through a callback that must not return: it records the message and longjmps back to
// the setjmp of the function that called libpng (PngInfo, PngTransforms, PngPixels; they hold no C++ objects). Warnings
// are ignored: libpng raises errors for what damages the pixels (a short or corrupt IDAT stream, a bad checksum).

struct PngSource {
  const std::string* bytes;
  size_t pos;
  char message[256];
};

void PngError(png_structp png, png_const_charp msg) {
  auto* src = static_cast<PngSource*>(png_get_error_ptr(png));
  std::snprintf(src->message, sizeof src->message, "%s", msg ? msg : "error");
  png_longjmp(png, 1);
}
void PngWarning(png_structp, png_const_charp) {}

void PngRead(png_structp png, png_bytep out, png_size_t n) {
  auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
  if (src->pos + n > src->bytes->size()) png_error(png, "the file ends early (truncated)");
  std::memcpy(out, src->bytes->data() + src->pos, n);
  src->pos += n;
}

// The header (IHDR and the chunks before the pixels); nothing the size of the image is allocated yet.
bool PngInfo(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  return true;
}

// The transforms to 8/16-bit grey, grey + alpha, RGB or RGBA (libpng allocates its row buffers here).
bool PngTransforms(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  const int type = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16) png_set_swap(png);  // native (little-endian) 16-bit samples
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  return true;
}

// The channels and bits per channel that PngTransforms gives, from the header.
void PngOutputFormat(png_structp png, png_infop info, int* channels, int* bits) {
  const int type = png_get_color_type(png, info);
  const bool trns = png_get_valid(png, info, PNG_INFO_tRNS) != 0;
  *channels = type == PNG_COLOR_TYPE_GRAY         ? 1 + trns
              : type == PNG_COLOR_TYPE_GRAY_ALPHA ? 2
              : type == PNG_COLOR_TYPE_RGB_ALPHA  ? 4
                                                  : 3 + trns;  // RGB, palette
  *bits = png_get_bit_depth(png, info) == 16 ? 16 : 8;
}

bool PngPixels(png_structp png, png_infop info, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, info);
  return true;
}

// The chunk structure, walked before libpng sees the file: every chunk's declared length must lie within the
// file (libpng allocates a chunk's declared length before it reads it: 2 GB for a damaged tEXt length field).
void CheckPngChunks(const std::string& b, const std::string& where) {
  size_t pos = 8;
  while (pos < b.size()) {
    HOVS_REQUIRE(b.size() - pos >= 12, where, "truncated PNG (a chunk header is cut off at byte ", pos, ")");
    const auto* p = reinterpret_cast<const unsigned char*>(b.data() + pos);
    const uint64_t length = (uint64_t(p[0]) << 24) | (uint64_t(p[1]) << 16) | (uint64_t(p[2]) << 8) | p[3];
    HOVS_REQUIRE(length <= b.size() - pos - 12, where, "corrupt or truncated PNG: a chunk at byte ", pos, " declares ",
                 length, " bytes, past the end of the file");
    if (std::memcmp(p + 4, "IEND", 4) == 0) return;
    pos += 12 + length;
  }
  throw Error(where, "truncated PNG (no IEND chunk)");
}

// ------------------------------------------------------------------------------------------------- JPEG
// libjpeg's errors and its warnings about damaged data (a truncated file, corrupt entropy-coded data) end the
// decode: the message is recorded and the decoder longjmps back (JpegHeader, JpegPixels). Warnings that do not
// touch the pixels (extra bytes between markers, an unusual JFIF version, an ICC profile) are ignored.

struct JpegErrors {
  jpeg_error_mgr mgr;
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void JpegErrorExit(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<JpegErrors*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  longjmp(err->jump, 1);
}

void JpegEmit(j_common_ptr cinfo, int level) {
  if (level >= 0) return;  // trace messages
  const int code = cinfo->err->msg_code;
  if (code == JWRN_EXTRANEOUS_DATA || code == JWRN_JFIF_MAJOR || code == JWRN_ADOBE_XFORM || code == JWRN_BOGUS_ICC)
    return;
  JpegErrorExit(cinfo);
}

void JpegSilent(j_common_ptr) {}

bool JpegHeader(jpeg_decompress_struct* cinfo, const unsigned char* data, unsigned long size) {
  auto* err = reinterpret_cast<JpegErrors*>(cinfo->err);
  if (setjmp(err->jump)) return false;
  jpeg_mem_src(cinfo, data, size);
  jpeg_read_header(cinfo, TRUE);
  return true;
}

bool JpegPixels(jpeg_decompress_struct* cinfo, unsigned char* out, size_t row_bytes) {
  auto* err = reinterpret_cast<JpegErrors*>(cinfo->err);
  if (setjmp(err->jump)) return false;
  jpeg_start_decompress(cinfo);
  while (cinfo->output_scanline < cinfo->output_height) {
    JSAMPROW row = out + size_t(cinfo->output_scanline) * row_bytes;
    jpeg_read_scanlines(cinfo, &row, 1);
  }
  jpeg_finish_decompress(cinfo);
  return true;
}

}  // namespace

bool IsPng(const std::string& b) {
  return b.size() >= 8 && png_sig_cmp(reinterpret_cast<png_const_bytep>(b.data()), 0, 8) == 0;
}

bool IsJpeg(const std::string& b) {
  return b.size() >= 3 && uint8_t(b[0]) == 0xFF && uint8_t(b[1]) == 0xD8 && uint8_t(b[2]) == 0xFF;
}

Decoded DecodePng(const std::string& bytes, const std::string& where, bool pixels, SizeCheck check) {
  CheckPngChunks(bytes, where);
  PngSource src{&bytes, 0, {0}};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &src, PngError, PngWarning);
  HOVS_REQUIRE(png != nullptr, where, "cannot start the PNG decoder");
  png_infop info = png_create_info_struct(png);
  struct Cleanup {
    png_structp* png;
    png_infop* info;
    ~Cleanup() { png_destroy_read_struct(png, info, nullptr); }
  } cleanup{&png, &info};
  HOVS_REQUIRE(info != nullptr, where, "cannot start the PNG decoder");
  png_set_read_fn(png, &src, PngRead);
  // libpng's own limits on the declared size: hovs' (CheckSize refuses less; these keep libpng from allocating
  // for more than that before it).
  png_set_user_limits(png, 65535, 65535);
  // No chunk (or decompressed text or profile) larger than the file itself or 8 MB: a header may declare 2 GB.
  png_set_chunk_malloc_max(png, std::max<png_alloc_size_t>(bytes.size(), 8 << 20));
  Decoded d;
  HOVS_REQUIRE(PngInfo(png, info), where, "not a readable PNG: ", src.message);
  d.width = static_cast<int>(png_get_image_width(png, info));
  d.height = static_cast<int>(png_get_image_height(png, info));
  PngOutputFormat(png, info, &d.channels, &d.bits);
  check(where, d.width, d.height, d.channels, d.bits);
  HOVS_REQUIRE(PngTransforms(png, info), where, "not a readable PNG: ", src.message);
  HOVS_REQUIRE(png_get_channels(png, info) == d.channels && png_get_bit_depth(png, info) == d.bits, where,
               "unsupported PNG colour format");
  if (!pixels) return d;
  const size_t row = size_t(d.width) * d.channels * (d.bits / 8);
  d.samples.resize(row * d.height);
  std::vector<png_bytep> rows(d.height);
  for (int y = 0; y < d.height; ++y) rows[y] = d.samples.data() + size_t(y) * row;
  HOVS_REQUIRE(PngPixels(png, info, rows.data()), where, "corrupt or truncated PNG: ", src.message);
  return d;
}

Decoded DecodeJpeg(const std::string& bytes, const std::string& where, bool pixels, SizeCheck check) {
  jpeg_decompress_struct cinfo;
  JpegErrors err;
  std::memset(err.message, 0, sizeof err.message);
  cinfo.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = JpegErrorExit;
  err.mgr.emit_message = JpegEmit;
  err.mgr.output_message = JpegSilent;
  jpeg_create_decompress(&cinfo);
  struct Cleanup {
    jpeg_decompress_struct* c;
    ~Cleanup() { jpeg_destroy_decompress(c); }
  } cleanup{&cinfo};
  HOVS_REQUIRE(JpegHeader(&cinfo, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()), where,
               "not a readable JPEG: ", err.message);
  HOVS_REQUIRE(cinfo.jpeg_color_space != JCS_CMYK && cinfo.jpeg_color_space != JCS_YCCK, where,
               "CMYK JPEG images are not supported (grey or colour expected)");
  cinfo.out_color_space = cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  Decoded d;
  d.width = static_cast<int>(cinfo.image_width), d.height = static_cast<int>(cinfo.image_height);
  d.channels = cinfo.num_components == 1 ? 1 : 3, d.bits = 8;
  check(where, d.width, d.height, d.channels, d.bits);
  if (!pixels) return d;
  const size_t row = size_t(d.width) * d.channels;
  d.samples.resize(row * d.height);
  HOVS_REQUIRE(JpegPixels(&cinfo, d.samples.data(), row), where, "corrupt or truncated JPEG: ", err.message);
  return d;
}

std::string PngVersion() { return png_get_libpng_ver(nullptr); }

std::string JpegVersion() {
#ifdef LIBJPEG_TURBO_VERSION
#define HOVS_STR2(x) #x
#define HOVS_STR(x) HOVS_STR2(x)
  return std::string("libjpeg-turbo ") + HOVS_STR(LIBJPEG_TURBO_VERSION);
#else
  return "libjpeg " + std::to_string(JPEG_LIB_VERSION);
#endif
}

}  // namespace hovs::io::internal
