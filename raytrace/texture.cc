#include "raytrace/texture.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace hovs::raytrace {

ImageTexture ImageTexture::Load(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  HOVS_REQUIRE(in != nullptr, path, "cannot read texture image: ", OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  ImageTexture t;
  t.width = spec.width, t.height = spec.height, t.channels = 3, t.source = path;
  HOVS_REQUIRE(t.width > 0 && t.height > 0, path, "empty image");
  std::vector<float> raw(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, raw.data());
  in->close();
  HOVS_REQUIRE(ok, path, "cannot decode texture image: ", in->geterror());
  t.pixels.resize(static_cast<size_t>(t.width) * t.height * 3);
  for (size_t i = 0; i < static_cast<size_t>(t.width) * t.height; ++i)
    for (int c = 0; c < 3; ++c) t.pixels[3 * i + c] = raw[i * spec.nchannels + std::min(c, spec.nchannels - 1)];
  return t;
}

ImageTexture ImageTexture::FromGray8(const uint8_t* data, int width, int height, const std::string& source) {
  ImageTexture t;
  t.width = width, t.height = height, t.source = source;
  t.pixels.resize(static_cast<size_t>(width) * height * 3);
  for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i)
    t.pixels[3 * i] = t.pixels[3 * i + 1] = t.pixels[3 * i + 2] = data[i] / 255.0f;
  return t;
}

Rgb ImageTexture::Sample(double x, double y) const {
  x = std::clamp(x, 0.0, width - 1.0);
  y = std::clamp(y, 0.0, height - 1.0);
  const int x0 = std::min(static_cast<int>(x), width - 2 < 0 ? 0 : width - 2);
  const int y0 = std::min(static_cast<int>(y), height - 2 < 0 ? 0 : height - 2);
  const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  Rgb out;
  for (int c = 0; c < 3; ++c) {
    const auto p = [&](int xx, int yy) { return pixels[(static_cast<size_t>(yy) * width + xx) * 3 + c]; };
    out[c] = (1 - fy) * ((1 - fx) * p(x0, y0) + fx * p(x1, y0)) + fy * ((1 - fx) * p(x0, y1) + fx * p(x1, y1));
  }
  return out;
}

namespace {

uint32_t Hash(int32_t x, int32_t y, uint32_t seed) {
  uint32_t h = seed * 0x9E3779B9u ^ static_cast<uint32_t>(x) * 0x85EBCA6Bu ^ static_cast<uint32_t>(y) * 0xC2B2AE35u;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  return h;
}

double ValueNoise(double x, double y, uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy);
  const double tx = x - fx, ty = y - fy;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const auto v = [&](int32_t a, int32_t b) { return Hash(a, b, seed) * (1.0 / 4294967295.0); };
  return (1 - sy) * ((1 - sx) * v(ix, iy) + sx * v(ix + 1, iy)) + sy * ((1 - sx) * v(ix, iy + 1) + sx * v(ix + 1, iy + 1));
}

Rgb Mix(const Rgb& a, const Rgb& b, double t) {
  const float f = static_cast<float>(t);
  return {a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
}

}  // namespace

Rgb Texture::Eval(double s, double t) const {
  switch (kind) {
    case Kind::kSolid: return colour_a;
    case Kind::kChecker: {
      // Square (0, 0) is the one at the board's (-x, -y) corner; it is dark.
      const double x = s / square + 0.5 * squares_x, y = t / square + 0.5 * squares_y;
      if (x < 0 || y < 0 || x >= squares_x || y >= squares_y) return margin;
      const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
      return ((ix + iy) & 1) ? colour_b : colour_a;
    }
    case Kind::kImage: {
      if (!image) return colour_a;
      const double u = (s / image_width + 0.5) * image->width - 0.5;
      const double v = (0.5 - t / image_height) * image->height - 0.5;  // image rows go down, t goes up
      if (u < -0.5 || v < -0.5 || u > image->width - 0.5 || v > image->height - 0.5) return margin;
      return image->Sample(u, v);
    }
    case Kind::kNoise: {
      double acc = 0, amp = 1, norm = 0, freq = 1.0 / scale;
      for (int o = 0; o < octaves; ++o) {
        acc += amp * ValueNoise(s * freq, t * freq, seed + 7919u * o);
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
      }
      return Mix(colour_a, colour_b, acc / norm);
    }
  }
  return colour_a;
}

}  // namespace hovs::raytrace
