#include "unwrap/remap_kernels.h"

#include <immintrin.h>

#include <cstring>

namespace hovs::unwrap::kernels {
namespace {

constexpr int32_t kHalf = 1 << 9;   // half of a 1/64 px step: rounds positions to the nearest 1/64 px

inline int Lerp6(int a, int b, int f) { return a * (64 - f) + b * f; }

// One colour grid of an RGGB mosaic (element (i, j) at mosaic (2i + ox, 2j + oy)): the vertical-and-horizontal
// sum before the final shift (weights total 4096).
inline int GridSum(const uint8_t* src, ptrdiff_t stride, int32_t x, int32_t y, int ox, int oy) {
  const int32_t px = ((x - ox * 65536) >> 1) + kHalf, py = ((y - oy * 65536) >> 1) + kHalf;
  const int fx = (px >> 10) & 63, fy = (py >> 10) & 63;
  const uint8_t* p = src + (2 * (py >> 16) + oy) * stride + 2 * (px >> 16) + ox;
  return Lerp6(p[0], p[2], fx) * (64 - fy) + Lerp6(p[2 * stride], p[2 * stride + 2], fx) * fy;
}

}  // namespace

bool HaveAvx2() {
  static const bool have = __builtin_cpu_supports("avx2");
  return have;
}

void BilinearRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                          uint8_t* o) {
  for (int k = 0; k < n; ++k) {
    const int i = k;
    const int32_t x = c.X(i0 + k) + kHalf, y = c.Y(i0 + k) + kHalf;
    const int fx = (x >> 10) & 63, fy = (y >> 10) & 63;
    const uint8_t* q = src + (y >> 16) * stride + (x >> 16) * 3;
    for (int ch = 0; ch < 3; ++ch) {
      const int t = Lerp6(q[ch], q[ch + 3], fx), b = Lerp6(q[ch + stride], q[ch + stride + 3], fx);
      o[3 * i + ch] = static_cast<uint8_t>((t * (64 - fy) + b * fy + 2048) >> 12);
    }
  }
}

void BilinearGrayRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                           uint8_t* o) {
  for (int i = 0; i < n; ++i) {
    const int32_t x = c.X(i0 + i) + kHalf, y = c.Y(i0 + i) + kHalf;
    const int fx = (x >> 10) & 63, fy = (y >> 10) & 63;
    const uint8_t* q = src + (y >> 16) * stride + (x >> 16);
    const int t = Lerp6(q[0], q[1], fx), b = Lerp6(q[stride], q[stride + 1], fx);
    o[i] = static_cast<uint8_t>((t * (64 - fy) + b * fy + 2048) >> 12);
  }
}

void BayerRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                       uint8_t* o) {
  for (int i = 0; i < n; ++i) {
    const int32_t x = c.X(i0 + i), y = c.Y(i0 + i);
    o[3 * i] = static_cast<uint8_t>((GridSum(src, stride, x, y, 0, 0) + 2048) >> 12);
    o[3 * i + 1] =
        static_cast<uint8_t>((GridSum(src, stride, x, y, 1, 0) + GridSum(src, stride, x, y, 0, 1) + 4096) >> 13);
    o[3 * i + 2] = static_cast<uint8_t>((GridSum(src, stride, x, y, 1, 1) + 2048) >> 12);
  }
}

namespace {

// Coordinates of pixels i .. i + 7 of a row: loaded, or the row polynomial evaluated in the same float
// operations as RowPoly::X (so the scalar and vector paths agree bit for bit).
__attribute__((target("avx2"))) inline void Coords8(const RowCoords& c, int i, __m256i* x, __m256i* y) {
  if (c.xs) {
    *x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.xs + i));
    *y = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.ys + i));
    return;
  }
  const __m256 fi = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(i), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)));
  const __m256i one = _mm256_set1_epi32(65536);
  const RowPoly& p = c.poly;
  const __m256 px = _mm256_add_ps(_mm256_set1_ps(p.bx),
                                  _mm256_mul_ps(fi, _mm256_add_ps(_mm256_set1_ps(p.c1x), _mm256_mul_ps(fi, _mm256_set1_ps(p.c2x)))));
  const __m256 py = _mm256_add_ps(_mm256_set1_ps(p.by),
                                  _mm256_mul_ps(fi, _mm256_add_ps(_mm256_set1_ps(p.c1y), _mm256_mul_ps(fi, _mm256_set1_ps(p.c2y)))));
  *x = _mm256_sub_epi32(_mm256_cvttps_epi32(px), one);
  *y = _mm256_sub_epi32(_mm256_cvttps_epi32(py), one);
}

// Stores 8 pixels whose RGB0 dwords are in p (pixels 0-3 in the low lane, 4-7 in the high lane) as 24 bytes.
__attribute__((target("avx2"))) inline void StoreRgb8(__m256i p, uint8_t* d) {
  const __m256i drop = _mm256_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1,
                                        0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
  p = _mm256_shuffle_epi8(p, drop);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(d), _mm256_castsi256_si128(p));   // 16 bytes: 4 spill, rewritten
  const __m128i hi = _mm256_extracti128_si256(p, 1);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(d + 12), hi);
  const int last = _mm_extract_epi32(hi, 2);
  std::memcpy(d + 20, &last, 4);
}

// 8 pixels per step. The two source pixels of each row are read with one unaligned 64-bit load per pixel and
// row (R0 G0 B0 R1 G1 B1 . .): cheaper than gathers on the machines measured (AMD Zen 3: 2x).
__attribute__((target("avx2"))) void BilinearRgbRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c,
                                                         int i0, int n, uint8_t* o) {
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63), c64 = _mm256_set1_epi32(64);
  const __m256i vstride = _mm256_set1_epi32(static_cast<int>(stride));
  const __m256i round = _mm256_set1_epi32(1 << 11);
  // (left, right) byte pairs of R, G, B for the two pixels of each 128-bit lane.
  const __m256i pairs = _mm256_setr_epi8(0, 3, 1, 4, 2, 5, -1, -1, 8, 11, 9, 12, 10, 13, -1, -1,
                                         0, 3, 1, 4, 2, 5, -1, -1, 8, 11, 9, 12, 10, 13, -1, -1);
  const __m256i rep = _mm256_setr_epi8(0, 1, 0, 1, 0, 1, 0, 1, 4, 5, 4, 5, 4, 5, 4, 5,
                                       0, 1, 0, 1, 0, 1, 0, 1, 4, 5, 4, 5, 4, 5, 4, 5);
  const uint8_t* d2 = data + stride;
  alignas(32) int32_t off[8];
  const auto load = [](const uint8_t* p) {
    long long v;
    std::memcpy(&v, p, 8);
    return v;
  };
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256i x, y;
    Coords8(c, i0 + i, &x, &y);
    x = _mm256_add_epi32(x, half);
    y = _mm256_add_epi32(y, half);
    const __m256i ix = _mm256_srai_epi32(x, 16), iy = _mm256_srai_epi32(y, 16);
    const __m256i fx = _mm256_and_si256(_mm256_srai_epi32(x, 10), m63);
    const __m256i fy = _mm256_and_si256(_mm256_srai_epi32(y, 10), m63);
    _mm256_store_si256(reinterpret_cast<__m256i*>(off),
                       _mm256_add_epi32(_mm256_mullo_epi32(iy, vstride), _mm256_add_epi32(ix, _mm256_add_epi32(ix, ix))));
    // Registers A hold pixels 0, 1 | 2, 3 and B pixels 4, 5 | 6, 7 (two per 128-bit lane).
    const __m256i tA = _mm256_setr_epi64x(load(data + off[0]), load(data + off[1]), load(data + off[2]), load(data + off[3]));
    const __m256i tB = _mm256_setr_epi64x(load(data + off[4]), load(data + off[5]), load(data + off[6]), load(data + off[7]));
    const __m256i bA = _mm256_setr_epi64x(load(d2 + off[0]), load(d2 + off[1]), load(d2 + off[2]), load(d2 + off[3]));
    const __m256i bB = _mm256_setr_epi64x(load(d2 + off[4]), load(d2 + off[5]), load(d2 + off[6]), load(d2 + off[7]));
    const __m256i wxd = _mm256_or_si256(_mm256_slli_epi32(fx, 8), _mm256_sub_epi32(c64, fx));
    const __m256i wyd = _mm256_or_si256(_mm256_slli_epi32(fy, 16), _mm256_sub_epi32(c64, fy));
    const __m256i wxA = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(wxd, _mm256_setr_epi32(0, 1, 0, 0, 2, 3, 0, 0)), rep);
    const __m256i wxB = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(wxd, _mm256_setr_epi32(4, 5, 0, 0, 6, 7, 0, 0)), rep);
    // Horizontal: R G B 0 per pixel (16-bit).
    const __m256i htA = _mm256_maddubs_epi16(_mm256_shuffle_epi8(tA, pairs), wxA);
    const __m256i htB = _mm256_maddubs_epi16(_mm256_shuffle_epi8(tB, pairs), wxB);
    const __m256i hbA = _mm256_maddubs_epi16(_mm256_shuffle_epi8(bA, pairs), wxA);
    const __m256i hbB = _mm256_maddubs_epi16(_mm256_shuffle_epi8(bB, pairs), wxB);
    // Vertical: (top, bottom) pairs times (64 - fy, fy), 32-bit.
    __m256i r0 = _mm256_madd_epi16(_mm256_unpacklo_epi16(htA, hbA), _mm256_permutevar8x32_epi32(wyd, _mm256_setr_epi32(0, 0, 0, 0, 2, 2, 2, 2)));
    __m256i r1 = _mm256_madd_epi16(_mm256_unpackhi_epi16(htA, hbA), _mm256_permutevar8x32_epi32(wyd, _mm256_setr_epi32(1, 1, 1, 1, 3, 3, 3, 3)));
    __m256i r2 = _mm256_madd_epi16(_mm256_unpacklo_epi16(htB, hbB), _mm256_permutevar8x32_epi32(wyd, _mm256_setr_epi32(4, 4, 4, 4, 6, 6, 6, 6)));
    __m256i r3 = _mm256_madd_epi16(_mm256_unpackhi_epi16(htB, hbB), _mm256_permutevar8x32_epi32(wyd, _mm256_setr_epi32(5, 5, 5, 5, 7, 7, 7, 7)));
    r0 = _mm256_srli_epi32(_mm256_add_epi32(r0, round), 12);
    r1 = _mm256_srli_epi32(_mm256_add_epi32(r1, round), 12);
    r2 = _mm256_srli_epi32(_mm256_add_epi32(r2, round), 12);
    r3 = _mm256_srli_epi32(_mm256_add_epi32(r3, round), 12);
    // Packed dwords come out as pixels 0 1 4 5 | 2 3 6 7.
    __m256i p = _mm256_packus_epi16(_mm256_packus_epi32(r0, r1), _mm256_packus_epi32(r2, r3));
    p = _mm256_permutevar8x32_epi32(p, _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7));
    StoreRgb8(p, o + 3 * i);
  }
  BilinearRgbRowScalar(data, stride, c, i0 + i, n - i, o + 3 * i);
}

__attribute__((target("avx2"))) void BilinearGrayRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63), c64 = _mm256_set1_epi32(64);
  const __m256i vstride = _mm256_set1_epi32(static_cast<int>(stride));
  const __m256i round = _mm256_set1_epi32(1 << 11);
  const __m256i low16 = _mm256_set1_epi32(0xFFFF);
  const int* b0 = reinterpret_cast<const int*>(data);
  const int* b1 = reinterpret_cast<const int*>(data + stride);
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256i x, y;
    Coords8(c, i0 + i, &x, &y);
    x = _mm256_add_epi32(x, half);
    y = _mm256_add_epi32(y, half);
    const __m256i fx = _mm256_and_si256(_mm256_srai_epi32(x, 10), m63);
    const __m256i fy = _mm256_and_si256(_mm256_srai_epi32(y, 10), m63);
    const __m256i off = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_srai_epi32(y, 16), vstride), _mm256_srai_epi32(x, 16));
    const __m256i t = _mm256_and_si256(_mm256_i32gather_epi32(b0, off, 1), low16);   // p0 p1 0 0
    const __m256i b = _mm256_and_si256(_mm256_i32gather_epi32(b1, off, 1), low16);
    const __m256i wx = _mm256_or_si256(_mm256_slli_epi32(fx, 8), _mm256_sub_epi32(c64, fx));
    const __m256i ht = _mm256_maddubs_epi16(t, wx), hb = _mm256_maddubs_epi16(b, wx);   // h in the low 16 bits
    const __m256i wy = _mm256_or_si256(_mm256_slli_epi32(fy, 16), _mm256_sub_epi32(c64, fy));
    __m256i r = _mm256_madd_epi16(_mm256_or_si256(ht, _mm256_slli_epi32(hb, 16)), wy);
    r = _mm256_srli_epi32(_mm256_add_epi32(r, round), 12);
    r = _mm256_packus_epi16(_mm256_packus_epi32(r, r), r);   // bytes 0-3 of each lane
    const int lo = _mm256_cvtsi256_si32(r), hi = _mm256_extract_epi32(r, 4);
    std::memcpy(o + i, &lo, 4);
    std::memcpy(o + i + 4, &hi, 4);
  }
  BilinearGrayRowScalar(data, stride, c, i0 + i, n - i, o + i);
}

// One colour grid for 8 pixels: the weighted sum (weights total 4096), 32-bit.
__attribute__((target("avx2"))) inline __m256i GridSum8(const uint8_t* data, ptrdiff_t stride, __m256i x, __m256i y,
                                                        int ox, int oy) {
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63), c64 = _mm256_set1_epi32(64);
  const __m256i pairs = _mm256_set1_epi32(0x00FF00FF);
  const __m256i px = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(x, _mm256_set1_epi32(ox * 65536)), 1), half);
  const __m256i py = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(y, _mm256_set1_epi32(oy * 65536)), 1), half);
  const __m256i fx = _mm256_and_si256(_mm256_srai_epi32(px, 10), m63);
  const __m256i fy = _mm256_and_si256(_mm256_srai_epi32(py, 10), m63);
  const __m256i row = _mm256_slli_epi32(_mm256_srai_epi32(py, 16), 1);
  const __m256i col = _mm256_slli_epi32(_mm256_srai_epi32(px, 16), 1);
  const __m256i off = _mm256_add_epi32(_mm256_mullo_epi32(row, _mm256_set1_epi32(static_cast<int>(stride))), col);
  const int* b0 = reinterpret_cast<const int*>(data + oy * stride + ox);
  const int* b1 = reinterpret_cast<const int*>(data + (oy + 2) * stride + ox);
  const __m256i t = _mm256_and_si256(_mm256_i32gather_epi32(b0, off, 1), pairs);   // p0, p2 as 16-bit
  const __m256i b = _mm256_and_si256(_mm256_i32gather_epi32(b1, off, 1), pairs);
  const __m256i wx = _mm256_or_si256(_mm256_slli_epi32(fx, 16), _mm256_sub_epi32(c64, fx));
  const __m256i ht = _mm256_madd_epi16(t, wx), hb = _mm256_madd_epi16(b, wx);
  const __m256i wy = _mm256_or_si256(_mm256_slli_epi32(fy, 16), _mm256_sub_epi32(c64, fy));
  return _mm256_madd_epi16(_mm256_or_si256(ht, _mm256_slli_epi32(hb, 16)), wy);
}

__attribute__((target("avx2"))) void BayerRgbRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
  const __m256i r12 = _mm256_set1_epi32(1 << 11), r13 = _mm256_set1_epi32(1 << 12);
  // Lane order for StoreRgb8: pixels 0-3 in the low lane, 4-7 in the high lane: already the natural order.
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256i x, y;
    Coords8(c, i0 + i, &x, &y);
    const __m256i R = _mm256_srli_epi32(_mm256_add_epi32(GridSum8(data, stride, x, y, 0, 0), r12), 12);
    const __m256i G = _mm256_srli_epi32(
        _mm256_add_epi32(_mm256_add_epi32(GridSum8(data, stride, x, y, 1, 0), GridSum8(data, stride, x, y, 0, 1)), r13),
        13);
    const __m256i B = _mm256_srli_epi32(_mm256_add_epi32(GridSum8(data, stride, x, y, 1, 1), r12), 12);
    StoreRgb8(_mm256_or_si256(_mm256_or_si256(R, _mm256_slli_epi32(G, 8)), _mm256_slli_epi32(B, 16)), o + 3 * i);
  }
  BayerRgbRowScalar(data, stride, c, i0 + i, n - i, o + 3 * i);
}

}  // namespace

void BilinearRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  HaveAvx2() ? BilinearRgbRowAvx2(src, stride, c, i0, n, out) : BilinearRgbRowScalar(src, stride, c, i0, n, out);
}
void BilinearGrayRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  HaveAvx2() ? BilinearGrayRowAvx2(src, stride, c, i0, n, out) : BilinearGrayRowScalar(src, stride, c, i0, n, out);
}
void BayerRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  HaveAvx2() ? BayerRgbRowAvx2(src, stride, c, i0, n, out) : BayerRgbRowScalar(src, stride, c, i0, n, out);
}

}  // namespace hovs::unwrap::kernels
