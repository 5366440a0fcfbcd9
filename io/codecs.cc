#include "io/codecs.h"

#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <jpeglib.h>
#include <jerror.h>

#include <cstring>

#include "core/error.h"

namespace hovs::io::internal {
namespace {

// ------------------------------------------------------------------------------------------------- PNG
// libpng reports errors through a callback that must not return: it records the message and longjmps back to
// the setjmp of the function that called libpng (PngHeader, PngPixels; they hold no C++ objects). Warnings are
// ignored: libpng raises errors for what damages the pixels (a short or corrupt IDAT stream, a bad checksum).

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

// The header and the transforms to 8/16-bit grey, grey + alpha, RGB or RGBA. Returns false on an error.
bool PngHeader(png_structp png, png_infop info, int* width, int* height, int* channels, int* bits) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  const int type = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16) png_set_swap(png);   // native (little-endian) 16-bit samples
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  *width = static_cast<int>(png_get_image_width(png, info));
  *height = static_cast<int>(png_get_image_height(png, info));
  *channels = png_get_channels(png, info);
  *bits = png_get_bit_depth(png, info);
  return true;
}

bool PngPixels(png_structp png, png_infop info, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, info);
  return true;
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
  if (level >= 0) return;   // trace messages
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

bool IsPng(const std::string& b) { return b.size() >= 8 && png_sig_cmp(reinterpret_cast<png_const_bytep>(b.data()), 0, 8) == 0; }

bool IsJpeg(const std::string& b) {
  return b.size() >= 3 && uint8_t(b[0]) == 0xFF && uint8_t(b[1]) == 0xD8 && uint8_t(b[2]) == 0xFF;
}

Decoded DecodePng(const std::string& bytes, const std::string& where, bool pixels, SizeCheck check) {
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
  // Refuse absurd declared sizes inside libpng too (its own limit is 1e6 a side).
  png_set_user_limits(png, 0x7fffffff, 0x7fffffff);
  Decoded d;
  HOVS_REQUIRE(PngHeader(png, info, &d.width, &d.height, &d.channels, &d.bits), where, "not a readable PNG: ",
               src.message);
  check(where, d.width, d.height, d.channels, d.bits);
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
