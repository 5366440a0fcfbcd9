#include "unwrap/remap_kernels.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cstring>

namespace hovs::unwrap::kernels {
namespace {

constexpr int32_t kHalf = 1 << 9;   // half of a 1/64 px step: rounds positions to the nearest 1/64 px

inline int Lerp6(int a, int b, int f) { return a * (64 - f) + b * f; }

// The vertical step of the RGB and Bayer kernels in 16-bit arithmetic: t + round((b - t) * fy / 64), exactly as
// _mm256_mulhrs_epi16(b - t, fy << 9) rounds it (t, b: horizontal sums, at most 64 * 255).
inline int VerticalStep(int t, int b, int fy) { return t + (((b - t) * (fy << 9) + (1 << 14)) >> 15); }

// One colour grid of an RGGB mosaic (element (i, j) at mosaic (2i + ox, 2j + oy)) bilinearly at mosaic position
// (x, y), scaled by 64 (horizontal Lerp6, then VerticalStep: the AVX2 kernel's arithmetic).
inline int BayerGridValue(const uint8_t* src, ptrdiff_t stride, int32_t x, int32_t y, int ox, int oy) {
  const int32_t px = ((x - ox * 65536) >> 1) + kHalf, py = ((y - oy * 65536) >> 1) + kHalf;
  const int fx = (px >> 10) & 63, fy = (py >> 10) & 63;
  const uint8_t* p = src + (2 * (py >> 16) + oy) * stride + 2 * (px >> 16) + ox;
  return VerticalStep(Lerp6(p[0], p[2], fx), Lerp6(p[2 * stride], p[2 * stride + 2], fx), fy);
}

}  // namespace

const char* ToString(Isa isa) {
  return isa == Isa::kAvx512 ? "avx512" : isa == Isa::kAvx2 ? "avx2" : "scalar";
}

Isa DetectedIsa() {
  static const Isa isa = [] {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vbmi"))
      return Isa::kAvx512;
    return __builtin_cpu_supports("avx2") ? Isa::kAvx2 : Isa::kScalar;
  }();
  return isa;
}

namespace {
std::atomic<int> g_isa_limit{static_cast<int>(Isa::kAvx512)};
}  // namespace

Isa ActiveIsa() { return static_cast<Isa>(std::min(static_cast<int>(DetectedIsa()), g_isa_limit.load())); }
void LimitIsa(Isa max) { g_isa_limit = static_cast<int>(max); }

void BilinearRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                          uint8_t* o) {
  for (int k = 0; k < n; ++k) {
    const int i = k;
    const int32_t x = c.X(i0 + k) + kHalf, y = c.Y(i0 + k) + kHalf;
    const int fx = (x >> 10) & 63, fy = (y >> 10) & 63;
    const uint8_t* q = src + (y >> 16) * stride + (x >> 16) * 3;
    for (int ch = 0; ch < 3; ++ch) {
      const int t = Lerp6(q[ch], q[ch + 3], fx), b = Lerp6(q[ch + stride], q[ch + stride + 3], fx);
      o[3 * i + ch] = static_cast<uint8_t>((VerticalStep(t, b, fy) + 32) >> 6);
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
    const int r = BayerGridValue(src, stride, x, y, 0, 0), g1 = BayerGridValue(src, stride, x, y, 1, 0);
    const int g2 = BayerGridValue(src, stride, x, y, 0, 1), b = BayerGridValue(src, stride, x, y, 1, 1);
    o[3 * i] = static_cast<uint8_t>((r + 32) >> 6);
    o[3 * i + 1] = static_cast<uint8_t>((g1 + g2 + 64) >> 7);
    o[3 * i + 2] = static_cast<uint8_t>((b + 32) >> 6);
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
  const __m256i round = _mm256_set1_epi16(32);
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
    const __m256i wyd = _mm256_slli_epi32(fy, 9);   // fy << 9 in the low 16 bits
    const __m256i selA = _mm256_setr_epi32(0, 1, 0, 0, 2, 3, 0, 0), selB = _mm256_setr_epi32(4, 5, 0, 0, 6, 7, 0, 0);
    const __m256i wxA = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(wxd, selA), rep);
    const __m256i wxB = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(wxd, selB), rep);
    const __m256i wyA = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(wyd, selA), rep);
    const __m256i wyB = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(wyd, selB), rep);
    // Horizontal: R G B 0 per pixel (16-bit).
    const __m256i htA = _mm256_maddubs_epi16(_mm256_shuffle_epi8(tA, pairs), wxA);
    const __m256i htB = _mm256_maddubs_epi16(_mm256_shuffle_epi8(tB, pairs), wxB);
    const __m256i hbA = _mm256_maddubs_epi16(_mm256_shuffle_epi8(bA, pairs), wxA);
    const __m256i hbB = _mm256_maddubs_epi16(_mm256_shuffle_epi8(bB, pairs), wxB);
    // Vertical (VerticalStep), then (v + 32) >> 6.
    __m256i vA = _mm256_add_epi16(htA, _mm256_mulhrs_epi16(_mm256_sub_epi16(hbA, htA), wyA));
    __m256i vB = _mm256_add_epi16(htB, _mm256_mulhrs_epi16(_mm256_sub_epi16(hbB, htB), wyB));
    vA = _mm256_srli_epi16(_mm256_add_epi16(vA, round), 6);
    vB = _mm256_srli_epi16(_mm256_add_epi16(vB, round), 6);
    // Packed dwords come out as pixels 0 1 4 5 | 2 3 6 7.
    __m256i p = _mm256_packus_epi16(vA, vB);
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

// Eight pixels' 64-bit words at data + off[k] + d, each shuffled by its pixel's indices; packed order
// 0 1 4 5 | 2 3 6 7 (see BayerRgbRowAvx2).
__attribute__((target("avx2"))) inline __m256i BayerWord(const uint8_t* data, const int32_t* off, ptrdiff_t d,
                                                         __m256i idxA, __m256i idxB) {
  const auto load = [](const uint8_t* p) {
    long long v;
    std::memcpy(&v, p, 8);
    return v;
  };
  const __m256i a = _mm256_shuffle_epi8(
      _mm256_setr_epi64x(load(data + off[0] + d), load(data + off[1] + d), load(data + off[2] + d), load(data + off[3] + d)), idxA);
  const __m256i b = _mm256_shuffle_epi8(
      _mm256_setr_epi64x(load(data + off[4] + d), load(data + off[5] + d), load(data + off[6] + d), load(data + off[7] + d)), idxB);
  return _mm256_unpacklo_epi64(a, b);
}

// RGGB mosaic, 8 pixels per step, without gathers. For a pixel at mosaic column X (integer part) every tap of
// the four colour grids lies in the 8 bytes from column B = (X & ~1) - 2 (even, so R/G2 taps sit at even and
// G1/B taps at odd offsets 1..6 from it), and in four rows: two of the even-row grids (R, G1) and two of the
// odd-row grids (G2, B). So each pixel reads four 64-bit words; one byte shuffle per word picks the
// (left, right) taps of its two grids, the horizontal and vertical steps run on 16-bit pairs (R, G1) and
// (G2, B). Groups whose 8-byte read would pass the end of a row use the scalar kernel.
__attribute__((target("avx2"))) void BayerRgbRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63), c64 = _mm256_set1_epi32(64);
  const __m256i one = _mm256_set1_epi32(65536), lowmask = _mm256_set1_epi32(0xFFFF);
  const __m256i vstride = _mm256_set1_epi32(static_cast<int>(stride));
  const __m256i last_base = _mm256_set1_epi32(static_cast<int>(stride) - 8);
  const __m256i order = _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7);     // natural -> the packed order 0 1 4 5 | 2 3 6 7
  const __m256i natural = _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7);   // the packed order -> natural (self-inverse)
  // Per pixel, the shuffle dword (ce, ce + 2, co, co + 2) for its own 8-byte word: pixel k of a lane's pair
  // reads bytes 8k..8k+7, so its indices get + 8k; the upper two dwords of each lane are zeroed.
  const __m256i pair_add = _mm256_setr_epi32(0, 0x08080808, 0, 0, 0, 0x08080808, 0, 0);
  alignas(32) int32_t offe[8], offo[8];
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256i x, y;
    Coords8(c, i0 + i, &x, &y);
    const __m256i base = _mm256_sub_epi32(_mm256_andnot_si256(_mm256_set1_epi32(1), _mm256_srai_epi32(x, 16)),
                                          _mm256_set1_epi32(2));
    if (_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(base, last_base))) != 0) {
      BayerRgbRowScalar(data, stride, c, i0 + i, 8, o + 3 * i);
      continue;
    }
    // Grid coordinates (as BayerGridValue): even grids (ox or oy = 0) and odd grids (= 1).
    const __m256i pxe = _mm256_add_epi32(_mm256_srai_epi32(x, 1), half);
    const __m256i pxo = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(x, one), 1), half);
    const __m256i pye = _mm256_add_epi32(_mm256_srai_epi32(y, 1), half);
    const __m256i pyo = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(y, one), 1), half);
    const __m256i fxe = _mm256_and_si256(_mm256_srai_epi32(pxe, 10), m63);
    const __m256i fxo = _mm256_and_si256(_mm256_srai_epi32(pxo, 10), m63);
    const __m256i fye = _mm256_and_si256(_mm256_srai_epi32(pye, 10), m63);
    const __m256i fyo = _mm256_and_si256(_mm256_srai_epi32(pyo, 10), m63);
    const __m256i ce = _mm256_sub_epi32(_mm256_slli_epi32(_mm256_srai_epi32(pxe, 16), 1), base);
    const __m256i co = _mm256_sub_epi32(_mm256_add_epi32(_mm256_slli_epi32(_mm256_srai_epi32(pxo, 16), 1), _mm256_set1_epi32(1)), base);
    const __m256i rowe = _mm256_slli_epi32(_mm256_srai_epi32(pye, 16), 1);
    const __m256i rowo = _mm256_add_epi32(_mm256_slli_epi32(_mm256_srai_epi32(pyo, 16), 1), _mm256_set1_epi32(1));
    _mm256_store_si256(reinterpret_cast<__m256i*>(offe), _mm256_add_epi32(_mm256_mullo_epi32(rowe, vstride), base));
    _mm256_store_si256(reinterpret_cast<__m256i*>(offo), _mm256_add_epi32(_mm256_mullo_epi32(rowo, vstride), base));
    // Byte indices (ce, ce + 2, co, co + 2) per pixel, moved to the packed order (pixels 0 1 | 2 3 in A's lanes,
    // 4 5 | 6 7 in B's): A takes packed dwords 0, 1 and 4, 5 (pixels 0, 1, 2, 3), B dwords 2, 3 and 6, 7.
    const __m256i idx = _mm256_or_si256(_mm256_or_si256(ce, _mm256_slli_epi32(_mm256_add_epi32(ce, _mm256_set1_epi32(2)), 8)),
                                        _mm256_or_si256(_mm256_slli_epi32(co, 16), _mm256_slli_epi32(_mm256_add_epi32(co, _mm256_set1_epi32(2)), 24)));
    const __m256i zero_hi = _mm256_setr_epi32(0, 0, -1, -1, 0, 0, -1, -1);   // 0x80 bytes: pshufb writes zero
    const __m256i idxA = _mm256_or_si256(_mm256_add_epi8(_mm256_permutevar8x32_epi32(idx, _mm256_setr_epi32(0, 1, 0, 0, 2, 3, 0, 0)), pair_add),
                                         _mm256_and_si256(zero_hi, _mm256_set1_epi8(char(0x80))));
    const __m256i idxB = _mm256_or_si256(_mm256_add_epi8(_mm256_permutevar8x32_epi32(idx, _mm256_setr_epi32(4, 5, 0, 0, 6, 7, 0, 0)), pair_add),
                                         _mm256_and_si256(zero_hi, _mm256_set1_epi8(char(0x80))));
    const __m256i et = BayerWord(data, offe, 0, idxA, idxB), eb = BayerWord(data, offe, 2 * stride, idxA, idxB);
    const __m256i ot = BayerWord(data, offo, 0, idxA, idxB), ob = BayerWord(data, offo, 2 * stride, idxA, idxB);
    // Horizontal weights (64 - fxe, fxe, 64 - fxo, fxo) and vertical (fy << 9 in both words), packed order.
    const __m256i wx = _mm256_permutevar8x32_epi32(
        _mm256_or_si256(_mm256_or_si256(_mm256_sub_epi32(c64, fxe), _mm256_slli_epi32(fxe, 8)),
                        _mm256_or_si256(_mm256_slli_epi32(_mm256_sub_epi32(c64, fxo), 16), _mm256_slli_epi32(fxo, 24))),
        order);
    const __m256i wye = _mm256_permutevar8x32_epi32(_mm256_mullo_epi32(_mm256_slli_epi32(fye, 9), _mm256_set1_epi32(0x10001)), order);
    const __m256i wyo = _mm256_permutevar8x32_epi32(_mm256_mullo_epi32(_mm256_slli_epi32(fyo, 9), _mm256_set1_epi32(0x10001)), order);
    const __m256i het = _mm256_maddubs_epi16(et, wx), heb = _mm256_maddubs_epi16(eb, wx);   // (R, G1)
    const __m256i hot = _mm256_maddubs_epi16(ot, wx), hob = _mm256_maddubs_epi16(ob, wx);   // (G2, B)
    const __m256i ve = _mm256_add_epi16(het, _mm256_mulhrs_epi16(_mm256_sub_epi16(heb, het), wye));
    const __m256i vo = _mm256_add_epi16(hot, _mm256_mulhrs_epi16(_mm256_sub_epi16(hob, hot), wyo));
    const __m256i R = _mm256_srli_epi32(_mm256_add_epi32(_mm256_and_si256(ve, lowmask), _mm256_set1_epi32(32)), 6);
    const __m256i G = _mm256_srli_epi32(
        _mm256_add_epi32(_mm256_add_epi32(_mm256_srli_epi32(ve, 16), _mm256_and_si256(vo, lowmask)), _mm256_set1_epi32(64)), 7);
    const __m256i B = _mm256_srli_epi32(_mm256_add_epi32(_mm256_srli_epi32(vo, 16), _mm256_set1_epi32(32)), 6);
    const __m256i p = _mm256_or_si256(_mm256_or_si256(R, _mm256_slli_epi32(G, 8)), _mm256_slli_epi32(B, 16));
    StoreRgb8(_mm256_permutevar8x32_epi32(p, natural), o + 3 * i);
  }
  BayerRgbRowScalar(data, stride, c, i0 + i, n - i, o + 3 * i);
}

}  // namespace

void BilinearRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  switch (ActiveIsa()) {
    case Isa::kAvx512: return avx512::BilinearRgbRow(src, stride, c, i0, n, out);
    case Isa::kAvx2: return BilinearRgbRowAvx2(src, stride, c, i0, n, out);
    default: return BilinearRgbRowScalar(src, stride, c, i0, n, out);
  }
}
void BilinearGrayRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  switch (ActiveIsa()) {
    case Isa::kAvx512: return avx512::BilinearGrayRow(src, stride, c, i0, n, out);
    case Isa::kAvx2: return BilinearGrayRowAvx2(src, stride, c, i0, n, out);
    default: return BilinearGrayRowScalar(src, stride, c, i0, n, out);
  }
}
void BayerRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  switch (ActiveIsa()) {
    case Isa::kAvx512: return avx512::BayerRgbRow(src, stride, c, i0, n, out);
    case Isa::kAvx2: return BayerRgbRowAvx2(src, stride, c, i0, n, out);
    default: return BayerRgbRowScalar(src, stride, c, i0, n, out);
  }
}

namespace {

using RowKernel = void (*)(const uint8_t*, ptrdiff_t, const RowCoords&, int, int, uint8_t*);

// The scalar tile path: row by row through a small local buffer, then copied out.
void TileByRows(RowKernel row, int bytes_per_pixel, const uint8_t* src, ptrdiff_t stride, const Tile& t, int T,
                int nu, int nv, uint8_t* out, ptrdiff_t ostride) {
  alignas(64) uint8_t local[64 * 3 + 32];
  RowCoords c;
  for (int j = 0; j < nv; ++j) {
    c.poly = InterpRowPoly(t, T, j);
    row(src, stride, c, 0, nu, local);
    std::memcpy(out + j * ostride, local, size_t(nu) * bytes_per_pixel);
  }
}

}  // namespace

// The AVX2 tile functions (flatten: the row kernel inlined).
namespace {
HOVS_REMAP_TILE_FUNCTION(__attribute__((target("avx2"), flatten)), BilinearRgbTileAvx2, BilinearRgbRowAvx2)
HOVS_REMAP_TILE_FUNCTION(__attribute__((target("avx2"), flatten)), BilinearGrayTileAvx2, BilinearGrayRowAvx2)
HOVS_REMAP_TILE_FUNCTION(__attribute__((target("avx2"), flatten)), BayerRgbTileAvx2, BayerRgbRowAvx2)
}  // namespace

void BilinearRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                     ptrdiff_t ostride) {
  switch (ActiveIsa()) {
    case Isa::kAvx512: return avx512::BilinearRgbTile(src, stride, t, T, nu, nv, out, ostride);
    case Isa::kAvx2: return BilinearRgbTileAvx2(src, stride, t, T, nu, nv, out, ostride);
    default: return TileByRows(BilinearRgbRowScalar, 3, src, stride, t, T, nu, nv, out, ostride);
  }
}
void BilinearGrayTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                      ptrdiff_t ostride) {
  switch (ActiveIsa()) {
    case Isa::kAvx512: return avx512::BilinearGrayTile(src, stride, t, T, nu, nv, out, ostride);
    case Isa::kAvx2: return BilinearGrayTileAvx2(src, stride, t, T, nu, nv, out, ostride);
    default: return TileByRows(BilinearGrayRowScalar, 1, src, stride, t, T, nu, nv, out, ostride);
  }
}
void BayerRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                  ptrdiff_t ostride) {
  switch (ActiveIsa()) {
    case Isa::kAvx512: return avx512::BayerRgbTile(src, stride, t, T, nu, nv, out, ostride);
    case Isa::kAvx2: return BayerRgbTileAvx2(src, stride, t, T, nu, nv, out, ostride);
    default: return TileByRows(BayerRgbRowScalar, 3, src, stride, t, T, nu, nv, out, ostride);
  }
}

}  // namespace hovs::unwrap::kernels
