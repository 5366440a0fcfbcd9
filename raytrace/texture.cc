#include "raytrace/texture.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/vector_clones.h"
#include "io/image_io.h"

namespace hovs::raytrace {

ImageTexture ImageTexture::Load(const std::string& path) {
  int w = 0, h = 0, c = 0;
  const io::PixelBuffer raw = io::ReadImage(path, &w, &h, &c);
  ImageTexture t;
  t.width = w, t.height = h, t.channels = 3, t.source = path;
  t.pixels.resize(static_cast<size_t>(w) * h * 3);
  for (size_t i = 0; i < static_cast<size_t>(w) * h; ++i)
    for (int k = 0; k < 3; ++k) t.pixels[3 * i + k] = raw[i * c + std::min(k, c - 1)];
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

// The lattice hash of cell (x, y): seed * 0x9E3779B9 ^ x * 0x85EBCA6B ^ y * 0xC2B2AE35 (mod 2^32), then mixed.
// Its three products are taken as arguments (hs, hx, hy), so that neighbouring cells reuse them: (x + 1) K is
// x K + K modulo 2^32.
constexpr uint32_t kSeedFactor = 0x9E3779B9u, kXFactor = 0x85EBCA6Bu, kYFactor = 0xC2B2AE35u;
__attribute__((always_inline)) inline uint32_t Hash(uint32_t hs, uint32_t hx, uint32_t hy) {
  uint32_t h = hs ^ hx ^ hy;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  return h;
}

// The lattice value times 2^32: h converted through int32, for which there are vector instructions. (Helpers
// of a HOVS_VECTOR_CLONES function are always_inline and not lambdas: the AVX2 copy does not inline otherwise.)
__attribute__((always_inline)) inline float LatticeValue32(uint32_t hs, uint32_t hx, uint32_t hy) {
  return static_cast<float>(static_cast<int32_t>(Hash(hs, hx, hy) ^ 0x80000000u)) + 2147483648.0f;
}

// Value noise in single precision (32-bit floats and integers throughout, so that a vector holds as many
// coordinates as lattice hashes: 8 per AVX2 register), times 2^32: the lattice values h / 2^32 blended, with the
// power of two left to the caller (it scales every rounded result exactly, so the blend of h / 2^32 is this
// blend / 2^32 to the bit). Positions are in cells; single precision places them to 1e-4 cell at 2000 cells from
// the origin (0.5 um for the reference floor's finest octave). hs: the seed's product (seed * kSeedFactor).
__attribute__((always_inline)) inline float ValueNoise32(float x, float y, uint32_t hs) {
  // floor in single precision (one rounding instruction in the AVX2 and AVX-512 copies, a few SSE2 operations in
  // the baseline one with -fno-trapping-math; never a library call), then the integer. x - floor(x) is exact and
  // equals x - float(ix) (floats from 2^23 up are integers), so the cell and its offset are those of a truncation
  // and compare, with fewer operations (the kernel ran 8-15 % faster, BM_NoiseTexture).
  const float fx = __builtin_floorf(x), fy = __builtin_floorf(y);
  const int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy);
  const float tx = x - fx, ty = y - fy;
  const float sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const uint32_t hx0 = static_cast<uint32_t>(ix) * kXFactor, hx1 = hx0 + kXFactor;
  const uint32_t hy0 = static_cast<uint32_t>(iy) * kYFactor, hy1 = hy0 + kYFactor;
  const float v00 = LatticeValue32(hs, hx0, hy0), v10 = LatticeValue32(hs, hx1, hy0);
  const float v01 = LatticeValue32(hs, hx0, hy1), v11 = LatticeValue32(hs, hx1, hy1);
  return (1 - sy) * ((1 - sx) * v00 + sx * v10) + sy * ((1 - sx) * v01 + sx * v11);
}

// The noise texture's value in [0, 1] at n <= 256 points: octaves outside, points inside, so the inner loop
// vectorises. Texture::Eval calls it with n = 1, so both agree to the bit. T: the precision of the points
// (double, or float for the renderer's single-precision colour samples).
template <class T>
HOVS_VECTOR_CLONES void NoiseValues(int n, const T* __restrict s, const T* __restrict t, double scale, int octaves,
                                    uint32_t seed, float* __restrict out) {
  // Positions in base cells, clamped to +-5e5 so that the finest octave (12 at most, x 2048) stays within int32.
  float x[256], y[256];
  const T sc = static_cast<T>(scale), lo = static_cast<T>(-5e5), hi = static_cast<T>(5e5);
  for (int i = 0; i < n; ++i) {
    out[i] = 0;
    x[i] = static_cast<float>(std::min(std::max(s[i] / sc, lo), hi));
    y[i] = static_cast<float>(std::min(std::max(t[i] / sc, lo), hi));
  }
  float amp = 1, norm = 0, freq = 1;
  for (int o = 0; o < std::min(octaves, 12); ++o) {
    const uint32_t hs = (seed + 7919u * static_cast<uint32_t>(o)) * kSeedFactor;
    // amp (a power of two) / 2^32 times the blend: amp times the octave's value in [0, 1], to the bit.
    const float amp32 = amp * (1.0f / 4294967296.0f);
    for (int i = 0; i < n; ++i) out[i] += amp32 * ValueNoise32(x[i] * freq, y[i] * freq, hs);
    norm += amp;
    amp *= 0.5f;
    freq *= 2.0f;
  }
  for (int i = 0; i < n; ++i) out[i] /= norm;
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
      float value = 0;
      NoiseValues<double>(1, &s, &t, scale, octaves, seed, &value);
      return Mix(colour_a, colour_b, value);
    }
  }
  return colour_a;
}

namespace {

// Mix for n values into interleaved RGB (out[3k + c]): the same operations as Mix, vectorised.
HOVS_VECTOR_CLONES
void MixInto(int n, const float* __restrict v, const float* __restrict a, const float* __restrict b,
             float* __restrict out) {
  const float a0 = a[0], a1 = a[1], a2 = a[2], d0 = b[0] - a0, d1 = b[1] - a1, d2 = b[2] - a2;
  for (int k = 0; k < n; ++k) {
    out[3 * k] = a0 + v[k] * d0, out[3 * k + 1] = a1 + v[k] * d1, out[3 * k + 2] = a2 + v[k] * d2;
  }
}

// The checkerboard of Texture::Eval at n points into interleaved RGB, vectorised: the same double arithmetic and
// decisions (inside the squares; the square's parity), written as selects. Coordinates are clamped before the
// conversion to int (points outside take the margin colour whatever their square).
template <class T>
HOVS_VECTOR_CLONES void CheckerInto(int n, const T* __restrict s, const T* __restrict t, double square, int squares_x,
                                    int squares_y, const float* __restrict a, const float* __restrict b,
                                    const float* __restrict margin, float* __restrict out) {
  const double nx = squares_x, ny = squares_y, hx = 0.5 * squares_x, hy = 0.5 * squares_y;
  const float a0 = a[0], a1 = a[1], a2 = a[2], b0 = b[0], b1 = b[1], b2 = b[2];
  const float m0 = margin[0], m1 = margin[1], m2 = margin[2];
  for (int k = 0; k < n; ++k) {
    const double x = static_cast<double>(s[k]) / square + hx, y = static_cast<double>(t[k]) / square + hy;
    int inside = x >= 0 ? 1 : 0;
    inside = y >= 0 ? inside : 0;
    inside = x < nx ? inside : 0;
    inside = y < ny ? inside : 0;
    const int ix = static_cast<int>(std::min(std::max(x, 0.0), nx)),
              iy = static_cast<int>(std::min(std::max(y, 0.0), ny));
    const int light = (ix + iy) & 1;
    const float c0 = light ? b0 : a0, c1 = light ? b1 : a1, c2 = light ? b2 : a2;
    out[3 * k] = inside ? c0 : m0, out[3 * k + 1] = inside ? c1 : m1, out[3 * k + 2] = inside ? c2 : m2;
  }
}

template <class T>
void EvalIntoOf(const Texture& x, int n, const T* s, const T* t, float* rgb) {
  if (x.kind == Texture::Kind::kChecker) {
    CheckerInto<T>(n, s, t, x.square, x.squares_x, x.squares_y, x.colour_a.data(), x.colour_b.data(), x.margin.data(),
                   rgb);
  } else if (x.kind == Texture::Kind::kNoise) {
    constexpr int kBlock = 256;
    float value[kBlock];
    for (int i0 = 0; i0 < n; i0 += kBlock) {
      const int m = std::min(kBlock, n - i0);
      NoiseValues<T>(m, s + i0, t + i0, x.scale, x.octaves, x.seed, value);
      MixInto(m, value, x.colour_a.data(), x.colour_b.data(), rgb + 3 * i0);
    }
  } else {
    for (int i = 0; i < n; ++i) {
      const Rgb c = x.Eval(s[i], t[i]);
      rgb[3 * i] = c[0], rgb[3 * i + 1] = c[1], rgb[3 * i + 2] = c[2];
    }
  }
}

}  // namespace

void Texture::EvalInto(int n, const double* s, const double* t, float* rgb) const { EvalIntoOf(*this, n, s, t, rgb); }
void Texture::EvalInto(int n, const float* s, const float* t, float* rgb) const { EvalIntoOf(*this, n, s, t, rgb); }

}  // namespace hovs::raytrace
