#include "unwrap/remap_kernels.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cstring>

namespace hovs::unwrap::kernels {
namespace {

constexpr int32_t kHalf = 1 << 9;  // half of a 1/64 px step: rounds positions to the nearest 1/64 px

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

const char* ToString(Isa isa) { return isa == Isa::kAvx512 ? "avx512" : isa == Isa::kAvx2 ? "avx2" : "scalar"; }

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

void BilinearRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
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

void BilinearGrayRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
  for (int i = 0; i < n; ++i) {
    const int32_t x = c.X(i0 + i) + kHalf, y = c.Y(i0 + i) + kHalf;
    const int fx = (x >> 10) & 63, fy = (y >> 10) & 63;
    const uint8_t* q = src + (y >> 16) * stride + (x >> 16);
    const int t = Lerp6(q[0], q[1], fx), b = Lerp6(q[stride], q[stride + 1], fx);
    o[i] = static_cast<uint8_t>((t * (64 - fy) + b * fy + 2048) >> 12);
  }
}

void BayerRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
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
  const __m256 fi =
      _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(i), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)));
  const __m256i one = _mm256_set1_epi32(65536);
  const RowPoly& p = c.poly;
  const __m256 px =
      _mm256_add_ps(_mm256_set1_ps(p.bx),
                    _mm256_mul_ps(fi, _mm256_add_ps(_mm256_set1_ps(p.c1x), _mm256_mul_ps(fi, _mm256_set1_ps(p.c2x)))));
  const __m256 py =
      _mm256_add_ps(_mm256_set1_ps(p.by),
                    _mm256_mul_ps(fi, _mm256_add_ps(_mm256_set1_ps(p.c1y), _mm256_mul_ps(fi, _mm256_set1_ps(p.c2y)))));
  *x = _mm256_sub_epi32(_mm256_cvttps_epi32(px), one);
  *y = _mm256_sub_epi32(_mm256_cvttps_epi32(py), one);
}

// Stores 8 pixels whose RGB0 dwords are in p (pixels 0-3 in the low lane, 4-7 in the high lane) as 24 bytes.
__attribute__((target("avx2"))) inline void StoreRgb8(__m256i p, uint8_t* d) {
  const __m256i drop = _mm256_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1, 0, 1, 2, 4, 5, 6, 8, 9,
                                        10, 12, 13, 14, -1, -1, -1, -1);
  p = _mm256_shuffle_epi8(p, drop);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(d), _mm256_castsi256_si128(p));  // 16 bytes: 4 spill, rewritten
  const __m128i hi = _mm256_extracti128_si256(p, 1);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(d + 12), hi);
  const int last = _mm_extract_epi32(hi, 2);
  std::memcpy(d + 20, &last, 4);
}

// The byte offsets of 8 RGB pixels' top-left taps at 16.16 coordinates (x, y) in an image of row stride `stride`.
__attribute__((target("avx2"))) inline __m256i RgbOffsets8(ptrdiff_t stride, __m256i x, __m256i y) {
  const __m256i half = _mm256_set1_epi32(kHalf);
  const __m256i ix = _mm256_srai_epi32(_mm256_add_epi32(x, half), 16),
                iy = _mm256_srai_epi32(_mm256_add_epi32(y, half), 16);
  return _mm256_add_epi32(_mm256_mullo_epi32(iy, _mm256_set1_epi32(static_cast<int>(stride))),
                          _mm256_add_epi32(ix, _mm256_add_epi32(ix, ix)));
}

// 8 RGB pixels at 16.16 coordinates (x, y) whose tap offsets (RgbOffsets8) are off[0 .. 7], stored as 24 bytes
// at o. The two source pixels of each row are read with one unaligned 64-bit load per pixel and row
// (R0 G0 B0 R1 G1 B1 . .): cheaper than gathers on the machines measured (AMD Zen 3: 2x).
__attribute__((target("avx2"))) inline void RgbAt8(const uint8_t* data, ptrdiff_t stride, const int32_t* off, __m256i x,
                                                   __m256i y, uint8_t* o) {
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63), c64 = _mm256_set1_epi32(64);
  const __m256i round = _mm256_set1_epi16(32);
  // (left, right) byte pairs of R, G, B for the two pixels of each 128-bit lane.
  const __m256i pairs = _mm256_setr_epi8(0, 3, 1, 4, 2, 5, -1, -1, 8, 11, 9, 12, 10, 13, -1, -1, 0, 3, 1, 4, 2, 5, -1,
                                         -1, 8, 11, 9, 12, 10, 13, -1, -1);
  // Each pixel's 16-bit weight (the low word of its dword) repeated in its quadword: registers A hold pixels
  // 0, 1 | 4, 5 and B pixels 2, 3 | 6, 7 (two per 128-bit lane), so a pixel's weight already lies in its own
  // lane and one byte shuffle places it.
  const __m256i repA =
      _mm256_setr_epi8(0, 1, 0, 1, 0, 1, 0, 1, 4, 5, 4, 5, 4, 5, 4, 5, 0, 1, 0, 1, 0, 1, 0, 1, 4, 5, 4, 5, 4, 5, 4, 5);
  const __m256i repB = _mm256_setr_epi8(8, 9, 8, 9, 8, 9, 8, 9, 12, 13, 12, 13, 12, 13, 12, 13, 8, 9, 8, 9, 8, 9, 8, 9,
                                        12, 13, 12, 13, 12, 13, 12, 13);
  const uint8_t* d2 = data + stride;
  const auto load = [](const uint8_t* p) {
    long long v;
    std::memcpy(&v, p, 8);
    return v;
  };
  x = _mm256_add_epi32(x, half);
  y = _mm256_add_epi32(y, half);
  const __m256i fx = _mm256_and_si256(_mm256_srai_epi32(x, 10), m63);
  const __m256i fy = _mm256_and_si256(_mm256_srai_epi32(y, 10), m63);
  const __m256i tA =
      _mm256_setr_epi64x(load(data + off[0]), load(data + off[1]), load(data + off[4]), load(data + off[5]));
  const __m256i tB =
      _mm256_setr_epi64x(load(data + off[2]), load(data + off[3]), load(data + off[6]), load(data + off[7]));
  const __m256i bA = _mm256_setr_epi64x(load(d2 + off[0]), load(d2 + off[1]), load(d2 + off[4]), load(d2 + off[5]));
  const __m256i bB = _mm256_setr_epi64x(load(d2 + off[2]), load(d2 + off[3]), load(d2 + off[6]), load(d2 + off[7]));
  const __m256i wxd = _mm256_or_si256(_mm256_slli_epi32(fx, 8), _mm256_sub_epi32(c64, fx));
  const __m256i wyd = _mm256_slli_epi32(fy, 9);  // fy << 9 in the low 16 bits
  const __m256i wxA = _mm256_shuffle_epi8(wxd, repA), wxB = _mm256_shuffle_epi8(wxd, repB);
  const __m256i wyA = _mm256_shuffle_epi8(wyd, repA), wyB = _mm256_shuffle_epi8(wyd, repB);
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
  // Packed dwords come out in pixel order: 0 1 2 3 | 4 5 6 7.
  StoreRgb8(_mm256_packus_epi16(vA, vB), o);
}

// 8 pixels per step (RgbAt8).
__attribute__((target("avx2"))) void BilinearRgbRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c,
                                                        int i0, int n, uint8_t* o) {
  alignas(32) int32_t off[8];
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256i x, y;
    Coords8(c, i0 + i, &x, &y);
    _mm256_store_si256(reinterpret_cast<__m256i*>(off), RgbOffsets8(stride, x, y));
    RgbAt8(data, stride, off, x, y, o + 3 * i);
  }
  BilinearRgbRowScalar(data, stride, c, i0 + i, n - i, o + 3 * i);
}

// The value of 8 grey pixels from their taps (t: top row, b: bottom row, per dword the bytes p0 p1 0 0) and
// fractions fx, fy (1/64 px), stored as 8 bytes at o.
__attribute__((target("avx2"))) inline void GrayCombineAvx2(__m256i fx, __m256i fy, __m256i t, __m256i b, uint8_t* o) {
  const __m256i c64 = _mm256_set1_epi32(64), round = _mm256_set1_epi32(1 << 11);
  const __m256i wx = _mm256_or_si256(_mm256_slli_epi32(fx, 8), _mm256_sub_epi32(c64, fx));
  const __m256i ht = _mm256_maddubs_epi16(t, wx), hb = _mm256_maddubs_epi16(b, wx);  // h in the low 16 bits
  const __m256i wy = _mm256_or_si256(_mm256_slli_epi32(fy, 16), _mm256_sub_epi32(c64, fy));
  __m256i r = _mm256_madd_epi16(_mm256_or_si256(ht, _mm256_slli_epi32(hb, 16)), wy);
  r = _mm256_srli_epi32(_mm256_add_epi32(r, round), 12);
  r = _mm256_packus_epi16(_mm256_packus_epi32(r, r), r);  // bytes 0-3 of each lane
  const int lo = _mm256_cvtsi256_si32(r), hi = _mm256_extract_epi32(r, 4);
  std::memcpy(o, &lo, 4);
  std::memcpy(o + 4, &hi, 4);
}

__attribute__((target("avx2"))) void BilinearGrayRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c,
                                                         int i0, int n, uint8_t* o) {
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63);
  const __m256i vstride = _mm256_set1_epi32(static_cast<int>(stride));
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
    const __m256i off =
        _mm256_add_epi32(_mm256_mullo_epi32(_mm256_srai_epi32(y, 16), vstride), _mm256_srai_epi32(x, 16));
    const __m256i t = _mm256_and_si256(_mm256_i32gather_epi32(b0, off, 1), low16);  // p0 p1 0 0
    const __m256i b = _mm256_and_si256(_mm256_i32gather_epi32(b1, off, 1), low16);
    GrayCombineAvx2(fx, fy, t, b, o + i);
  }
  BilinearGrayRowScalar(data, stride, c, i0 + i, n - i, o + i);
}

// Eight pixels' 64-bit words at data + off[k] + d, each shuffled by its pixel's indices (PairShuffles), in
// pixel order: register a holds pixels 0, 1 | 4, 5, b pixels 2, 3 | 6, 7, and each 128-bit lane of the result
// takes the low halves of both.
__attribute__((target("avx2"))) inline __m256i BayerWord(const uint8_t* data, const int32_t* off, ptrdiff_t d,
                                                         __m256i idxA, __m256i idxB) {
  const auto load = [](const uint8_t* p) {
    long long v;
    std::memcpy(&v, p, 8);
    return v;
  };
  const __m256i a = _mm256_shuffle_epi8(_mm256_setr_epi64x(load(data + off[0] + d), load(data + off[1] + d),
                                                           load(data + off[4] + d), load(data + off[5] + d)),
                                        idxA);
  const __m256i b = _mm256_shuffle_epi8(_mm256_setr_epi64x(load(data + off[2] + d), load(data + off[3] + d),
                                                           load(data + off[6] + d), load(data + off[7] + d)),
                                        idxB);
  return _mm256_unpacklo_epi64(a, b);
}

// The colour grids' 16.16 positions of 8 pixels (as BayerGridValue): even grids (ox or oy = 0) and odd grids
// (= 1), with their 1/64 px fractions.
struct BayerGrids8 {
  __m256i pxe, pxo, pye, pyo, fxe, fxo, fye, fyo;
};
__attribute__((target("avx2"))) inline BayerGrids8 BayerGridsAt8(__m256i x, __m256i y) {
  const __m256i half = _mm256_set1_epi32(kHalf), one = _mm256_set1_epi32(65536), m63 = _mm256_set1_epi32(63);
  BayerGrids8 g;
  g.pxe = _mm256_add_epi32(_mm256_srai_epi32(x, 1), half);
  g.pxo = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(x, one), 1), half);
  g.pye = _mm256_add_epi32(_mm256_srai_epi32(y, 1), half);
  g.pyo = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(y, one), 1), half);
  g.fxe = _mm256_and_si256(_mm256_srai_epi32(g.pxe, 10), m63);
  g.fxo = _mm256_and_si256(_mm256_srai_epi32(g.pxo, 10), m63);
  g.fye = _mm256_and_si256(_mm256_srai_epi32(g.pye, 10), m63);
  g.fyo = _mm256_and_si256(_mm256_srai_epi32(g.pyo, 10), m63);
  return g;
}

// Per pixel (natural order) a shuffle dword for its own 8-byte word, to pshufb controls for the registers of
// pixels 0, 1 | 4, 5 (a) and 2, 3 | 6, 7 (b), two 8-byte words per 128-bit lane: pixel k of a lane's pair reads
// bytes 8k .. 8k + 7, so its indices get + 8k; the upper two dwords of each lane are zeroed (0x80). Each
// pixel's dword already lies in its register's lane: a takes dwords 0, 1 of each lane, b dwords 2, 3.
__attribute__((target("avx2"))) inline void PairShuffles(__m256i idx, __m256i* a, __m256i* b) {
  const __m256i pair_add = _mm256_setr_epi32(0, 0x08080808, 0, 0, 0, 0x08080808, 0, 0);
  const __m256i zero_hi =
      _mm256_setr_epi32(0, 0, int(0x80808080u), int(0x80808080u), 0, 0, int(0x80808080u), int(0x80808080u));
  *a = _mm256_or_si256(_mm256_add_epi8(idx, pair_add), zero_hi);
  *b = _mm256_or_si256(_mm256_add_epi8(_mm256_shuffle_epi32(idx, 0xEE), pair_add), zero_hi);  // dwords 2, 3, 2, 3
}

// The colour of 8 pixels from their mosaic taps (et, eb: the even-row grids' two tap rows, ot, ob: the odd-row
// grids'; per pixel (ce, ce + 2, co, co + 2)) and their grid fractions, all in pixel order, stored as 24 bytes
// at o.
__attribute__((target("avx2"))) inline void BayerCombineAvx2(__m256i fxe, __m256i fxo, __m256i fye, __m256i fyo,
                                                             __m256i et, __m256i eb, __m256i ot, __m256i ob,
                                                             uint8_t* o) {
  const __m256i c64 = _mm256_set1_epi32(64), lowmask = _mm256_set1_epi32(0xFFFF);
  // Horizontal weights (64 - fxe, fxe, 64 - fxo, fxo) and vertical (fy << 9 in both words).
  const __m256i wx =
      _mm256_or_si256(_mm256_or_si256(_mm256_sub_epi32(c64, fxe), _mm256_slli_epi32(fxe, 8)),
                      _mm256_or_si256(_mm256_slli_epi32(_mm256_sub_epi32(c64, fxo), 16), _mm256_slli_epi32(fxo, 24)));
  const __m256i wye = _mm256_mullo_epi32(_mm256_slli_epi32(fye, 9), _mm256_set1_epi32(0x10001));
  const __m256i wyo = _mm256_mullo_epi32(_mm256_slli_epi32(fyo, 9), _mm256_set1_epi32(0x10001));
  const __m256i het = _mm256_maddubs_epi16(et, wx), heb = _mm256_maddubs_epi16(eb, wx);  // (R, G1)
  const __m256i hot = _mm256_maddubs_epi16(ot, wx), hob = _mm256_maddubs_epi16(ob, wx);  // (G2, B)
  const __m256i ve = _mm256_add_epi16(het, _mm256_mulhrs_epi16(_mm256_sub_epi16(heb, het), wye));
  const __m256i vo = _mm256_add_epi16(hot, _mm256_mulhrs_epi16(_mm256_sub_epi16(hob, hot), wyo));
  const __m256i R = _mm256_srli_epi32(_mm256_add_epi32(_mm256_and_si256(ve, lowmask), _mm256_set1_epi32(32)), 6);
  const __m256i G =
      _mm256_srli_epi32(_mm256_add_epi32(_mm256_add_epi32(_mm256_srli_epi32(ve, 16), _mm256_and_si256(vo, lowmask)),
                                         _mm256_set1_epi32(64)),
                        7);
  const __m256i B = _mm256_srli_epi32(_mm256_add_epi32(_mm256_srli_epi32(vo, 16), _mm256_set1_epi32(32)), 6);
  const __m256i p = _mm256_or_si256(_mm256_or_si256(R, _mm256_slli_epi32(G, 8)), _mm256_slli_epi32(B, 16));
  StoreRgb8(p, o);
}

// RGGB mosaic, 8 pixels per step, without gathers. For a pixel at mosaic column X (integer part) every tap of
// the four colour grids lies in the 8 bytes from column B = (X & ~1) - 2 (even, so R/G2 taps sit at even and
// G1/B taps at odd offsets 1..6 from it), and in four rows: two of the even-row grids (R, G1) and two of the
// odd-row grids (G2, B). So each pixel reads four 64-bit words; one byte shuffle per word picks the
// (left, right) taps of its two grids, the horizontal and vertical steps run on 16-bit pairs (R, G1) and
// (G2, B). Groups whose 8-byte read would pass the end of a row use the scalar kernel.
__attribute__((target("avx2"))) void BayerRgbRowAvx2(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0,
                                                     int n, uint8_t* o) {
  const __m256i vstride = _mm256_set1_epi32(static_cast<int>(stride));
  const __m256i last_base = _mm256_set1_epi32(static_cast<int>(stride) - 8);
  alignas(32) int32_t offe[8], offo[8];
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256i x, y;
    Coords8(c, i0 + i, &x, &y);
    const __m256i base =
        _mm256_sub_epi32(_mm256_andnot_si256(_mm256_set1_epi32(1), _mm256_srai_epi32(x, 16)), _mm256_set1_epi32(2));
    if (_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(base, last_base))) != 0) {
      BayerRgbRowScalar(data, stride, c, i0 + i, 8, o + 3 * i);
      continue;
    }
    const BayerGrids8 g = BayerGridsAt8(x, y);
    const __m256i &pxe = g.pxe, &pxo = g.pxo, &pye = g.pye, &pyo = g.pyo;
    const __m256i ce = _mm256_sub_epi32(_mm256_slli_epi32(_mm256_srai_epi32(pxe, 16), 1), base);
    const __m256i co = _mm256_sub_epi32(
        _mm256_add_epi32(_mm256_slli_epi32(_mm256_srai_epi32(pxo, 16), 1), _mm256_set1_epi32(1)), base);
    const __m256i rowe = _mm256_slli_epi32(_mm256_srai_epi32(pye, 16), 1);
    const __m256i rowo = _mm256_add_epi32(_mm256_slli_epi32(_mm256_srai_epi32(pyo, 16), 1), _mm256_set1_epi32(1));
    _mm256_store_si256(reinterpret_cast<__m256i*>(offe), _mm256_add_epi32(_mm256_mullo_epi32(rowe, vstride), base));
    _mm256_store_si256(reinterpret_cast<__m256i*>(offo), _mm256_add_epi32(_mm256_mullo_epi32(rowo, vstride), base));
    // Byte indices (ce, ce + 2, co, co + 2) per pixel.
    const __m256i idx = _mm256_or_si256(
        _mm256_or_si256(ce, _mm256_slli_epi32(_mm256_add_epi32(ce, _mm256_set1_epi32(2)), 8)),
        _mm256_or_si256(_mm256_slli_epi32(co, 16), _mm256_slli_epi32(_mm256_add_epi32(co, _mm256_set1_epi32(2)), 24)));
    __m256i idxA, idxB;
    PairShuffles(idx, &idxA, &idxB);
    const __m256i et = BayerWord(data, offe, 0, idxA, idxB), eb = BayerWord(data, offe, 2 * stride, idxA, idxB);
    const __m256i ot = BayerWord(data, offo, 0, idxA, idxB), ob = BayerWord(data, offo, 2 * stride, idxA, idxB);
    BayerCombineAvx2(g.fxe, g.fxo, g.fye, g.fyo, et, eb, ot, ob, o + 3 * i);
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
void TileByRows(RowKernel row, int bytes_per_pixel, const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu,
                int nv, uint8_t* out, ptrdiff_t ostride) {
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
// Interp tiles as the AVX-512 ones (remap_kernels_avx512.cc): every pixel's coordinates first, with the source
// region the pixels' taps cover; that region copied into a patch (it stays in L1), for RGB as it is, for grey and
// Bayer with two source rows interleaved byte by byte (pair row k: rows r0 + k and r0 + k + 1, byte 2 j + s: row
// r0 + k + s, column c0 + j); then the pixels from the patch, whose taps come in the same order as from the
// frame, so the same bytes come out. A region too large for the patch goes row by row through the row kernel.
struct TilePassAvx2 {
  static constexpr int kColumns = 128,
                       kPairs = 128;  // pair patches; a plain (RGB) patch: kPairs rows of 2 kColumns bytes
  alignas(32) int32_t xs[64 * 64], ys[64 * 64];
  alignas(32) uint8_t patch[kPairs * 2 * kColumns];
  int row = 0;                             // coordinates kept per tile row (whole 8-pixel steps)
  int32_t x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // the extreme coordinates (16.16)

  __attribute__((target("avx2"))) void Coordinates(const Tile& t, int T, int nu, int nv) {
    row = (nu + 7) & ~7;
    __m256i xmin = _mm256_set1_epi32(INT32_MAX), xmax = _mm256_set1_epi32(INT32_MIN), ymin = xmin, ymax = xmax;
    RowPolys<8> polys;
    RowCoords c;
    for (int j = 0; j < nv; ++j) {
      if (j % 8 == 0) InterpRowPolys(t, T, j, &polys);
      c.poly = polys.Row(j % 8);
      for (int i = 0; i < nu; i += 8) {
        __m256i x, y;
        Coords8(c, i, &x, &y);
        if (nu - i < 8) {  // lanes past nu: lane 0's coordinates (inside the region, never stored)
          const __m256i live = _mm256_cmpgt_epi32(_mm256_set1_epi32(nu - i), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
          x = _mm256_blendv_epi8(_mm256_permutevar8x32_epi32(x, _mm256_setzero_si256()), x, live);
          y = _mm256_blendv_epi8(_mm256_permutevar8x32_epi32(y, _mm256_setzero_si256()), y, live);
        }
        _mm256_store_si256(reinterpret_cast<__m256i*>(xs + j * row + i), x);
        _mm256_store_si256(reinterpret_cast<__m256i*>(ys + j * row + i), y);
        xmin = _mm256_min_epi32(xmin, x), xmax = _mm256_max_epi32(xmax, x);
        ymin = _mm256_min_epi32(ymin, y), ymax = _mm256_max_epi32(ymax, y);
      }
    }
    alignas(32) int32_t v[4][8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(v[0]), xmin);
    _mm256_store_si256(reinterpret_cast<__m256i*>(v[1]), xmax);
    _mm256_store_si256(reinterpret_cast<__m256i*>(v[2]), ymin);
    _mm256_store_si256(reinterpret_cast<__m256i*>(v[3]), ymax);
    x0 = v[0][0], x1 = v[1][0], y0 = v[2][0], y1 = v[3][0];
    for (int k = 1; k < 8; ++k)
      x0 = std::min(x0, v[0][k]), x1 = std::max(x1, v[1][k]), y0 = std::min(y0, v[2][k]), y1 = std::max(y1, v[3][k]);
  }
  RowCoords Row(int j) const { return RowCoords{xs + j * row, ys + j * row, {}}; }
  // The patch pass of the RGB and Bayer tiles: step(off, j, i) for the 8 pixels from (i, j), where off holds the
  // 8 patch offsets offsets(j, i) of their words, computed and stored one tile row ahead of their use so that
  // the steps' scalar loads of them never wait on store-to-load forwarding (as the AVX-512 TilePass::PixelSteps).
  template <class Offsets, class Step>
  __attribute__((target("avx2"))) void PixelSteps(int nu, int nv, Offsets offsets, Step step) const {
    alignas(32) int32_t offs[2][64];
    const auto fill = [&](int j) __attribute__((target("avx2"))) {
      for (int i = 0; i < nu; i += 8) _mm256_store_si256(reinterpret_cast<__m256i*>(offs[j & 1] + i), offsets(j, i));
    };
    fill(0);
    for (int j = 0; j < nv; ++j) {
      if (j + 1 < nv) fill(j + 1);
      for (int i = 0; i < nu; i += 8) step(offs[j & 1] + i, j, i);
    }
  }
  __attribute__((target("avx2"))) __m256i X(int j, int i) const {
    return _mm256_load_si256(reinterpret_cast<const __m256i*>(xs + j * row + i));
  }
  __attribute__((target("avx2"))) __m256i Y(int j, int i) const {
    return _mm256_load_si256(reinterpret_cast<const __m256i*>(ys + j * row + i));
  }

  // The plain patch of source rows first .. first + rows - 1, bytes from .. from + bytes - 1 of each (only those
  // bytes are read); returns its row stride.
  __attribute__((target("avx2"))) ptrdiff_t Copy(const uint8_t* src, ptrdiff_t stride, int first, int rows,
                                                 ptrdiff_t from, int bytes) {
    const ptrdiff_t pstride = (bytes + 31) & ~31;
    for (int k = 0; k < rows; ++k) {
      const uint8_t* a = src + (first + k) * stride + from;
      uint8_t* d = patch + k * pstride;
      int b = 0;
      for (; b + 32 <= bytes; b += 32)
        _mm256_store_si256(reinterpret_cast<__m256i*>(d + b),
                           _mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + b)));
      std::memcpy(d + b, a + b, size_t(bytes - b));
    }
    return pstride;
  }
  // The kept coordinates of rows 0 .. nv - 1 moved by (-c0, -r0) whole pixels.
  __attribute__((target("avx2"))) void Shift(int nv, int c0, int r0) {
    const __m256i dx = _mm256_set1_epi32(c0 * 65536), dy = _mm256_set1_epi32(r0 * 65536);
    for (int k = 0; k < nv * row; k += 8) {
      _mm256_store_si256(reinterpret_cast<__m256i*>(xs + k), _mm256_sub_epi32(X(0, k), dx));
      _mm256_store_si256(reinterpret_cast<__m256i*>(ys + k), _mm256_sub_epi32(Y(0, k), dy));
    }
  }

  // The pair patch of source rows first .. first + pairs, columns from .. from + columns - 1 (only those bytes are
  // read); returns its row stride.
  __attribute__((target("avx2"))) ptrdiff_t CopyPairs(const uint8_t* src, ptrdiff_t stride, int first, int pairs,
                                                      int from, int columns) {
    const ptrdiff_t pstride = (2 * columns + 31) & ~31;
    for (int k = 0; k < pairs; ++k) {
      const uint8_t* a = src + (first + k) * stride + from;
      for (int cc = 0; cc < columns; cc += 16) {
        __m128i upper, lower;
        if (columns - cc >= 16) {
          upper = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a + cc));
          lower = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a + stride + cc));
        } else {
          alignas(16) uint8_t u[16] = {}, l[16] = {};
          std::memcpy(u, a + cc, size_t(columns - cc));
          std::memcpy(l, a + stride + cc, size_t(columns - cc));
          upper = _mm_load_si128(reinterpret_cast<const __m128i*>(u));
          lower = _mm_load_si128(reinterpret_cast<const __m128i*>(l));
        }
        _mm_store_si128(reinterpret_cast<__m128i*>(patch + k * pstride + 2 * cc), _mm_unpacklo_epi8(upper, lower));
        _mm_store_si128(reinterpret_cast<__m128i*>(patch + k * pstride + 2 * cc + 16), _mm_unpackhi_epi8(upper, lower));
      }
    }
    return pstride;
  }
};

// RGB: a pixel reads 8 bytes from 3 x its tap column in its tap row and the row below (BilinearRgbRowAvx2), so
// the region is bytes 3 c0 .. 3 c1 + 7 of rows r0 .. r1 + 1. It is copied as it is, the coordinates are moved
// to the patch's origin by whole pixels (the same fractions, so the same weights), and the row kernel reads the
// patch instead of the frame.
__attribute__((target("avx2"), flatten)) void BilinearRgbTileAvx2(const uint8_t* src, ptrdiff_t stride, const Tile& t,
                                                                  int T, int nu, int nv, uint8_t* out,
                                                                  ptrdiff_t ostride) {
  TilePassAvx2 p;
  p.Coordinates(t, T, nu, nv);
  const auto cell = [](int32_t q) { return (q + kHalf) >> 16; };
  const int c0 = cell(p.x0), r0 = cell(p.y0), bytes = 3 * (cell(p.x1) - c0) + 8, rows = cell(p.y1) - r0 + 2;
  if (bytes > 2 * TilePassAvx2::kColumns || rows > TilePassAvx2::kPairs) {
    for (int j = 0; j < nv; ++j) BilinearRgbRowAvx2(src, stride, p.Row(j), 0, nu, out + j * ostride);
    return;
  }
  const ptrdiff_t pstride = p.Copy(src, stride, r0, rows, 3 * ptrdiff_t(c0), bytes);
  p.Shift(nv, c0, r0);
  p.PixelSteps(
      nu, nv, [&](int j, int i) __attribute__((target("avx2"))) { return RgbOffsets8(pstride, p.X(j, i), p.Y(j, i)); },
      [&](const int32_t* off, int j, int i) __attribute__((target("avx2"))) {
        uint8_t* o = out + j * ostride + 3 * i;
        if (nu - i >= 8) {
          RgbAt8(p.patch, pstride, off, p.X(j, i), p.Y(j, i), o);
        } else {  // lanes past nu hold lane 0's coordinates
          uint8_t tail[24];
          RgbAt8(p.patch, pstride, off, p.X(j, i), p.Y(j, i), tail);
          std::memcpy(o, tail, size_t(3 * (nu - i)));
        }
      });
}

// Grey: a pixel's taps are columns c .. c + 1 of rows r .. r + 1 (c, r: (x + 1/128 px) >> 16), so one gathered
// 4-byte word of the patch (two per 8 pixels from the frame).
__attribute__((target("avx2"), flatten)) void BilinearGrayTileAvx2(const uint8_t* src, ptrdiff_t stride, const Tile& t,
                                                                   int T, int nu, int nv, uint8_t* out,
                                                                   ptrdiff_t ostride) {
  TilePassAvx2 p;
  p.Coordinates(t, T, nu, nv);
  const auto cell = [](int32_t q) { return (q + kHalf) >> 16; };
  const int c0 = cell(p.x0), c1 = cell(p.x1) + 1, r0 = cell(p.y0), pairs = cell(p.y1) - r0 + 1;
  const int columns = c1 - c0 + 1;
  if (columns > TilePassAvx2::kColumns || pairs > TilePassAvx2::kPairs) {
    for (int j = 0; j < nv; ++j) BilinearGrayRowAvx2(src, stride, p.Row(j), 0, nu, out + j * ostride);
    return;
  }
  const ptrdiff_t pstride = p.CopyPairs(src, stride, r0, pairs, c0, columns);
  const __m256i half = _mm256_set1_epi32(kHalf), m63 = _mm256_set1_epi32(63);
  const __m256i dx = _mm256_set1_epi32(c0), dy = _mm256_set1_epi32(r0),
                vpstride = _mm256_set1_epi32(static_cast<int>(pstride));
  // Per dword (p0, p1, 0, 0) of the top row and of the bottom row; pshufb indices count from the 128-bit lane.
  const __m256i lane = _mm256_setr_epi32(0, 0x04040404, 0x08080808, 0x0C0C0C0C, 0, 0x04040404, 0x08080808, 0x0C0C0C0C);
  const __m256i top = _mm256_add_epi8(_mm256_set1_epi32(int(0x80800200u)), lane);
  const __m256i bottom = _mm256_add_epi8(_mm256_set1_epi32(int(0x80800301u)), lane);
  const int* base = reinterpret_cast<const int*>(p.patch);
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; i += 8) {
      const __m256i x = _mm256_add_epi32(p.X(j, i), half), y = _mm256_add_epi32(p.Y(j, i), half);
      const __m256i fx = _mm256_and_si256(_mm256_srai_epi32(x, 10), m63);
      const __m256i fy = _mm256_and_si256(_mm256_srai_epi32(y, 10), m63);
      const __m256i ix = _mm256_sub_epi32(_mm256_srai_epi32(x, 16), dx),
                    iy = _mm256_sub_epi32(_mm256_srai_epi32(y, 16), dy);
      const __m256i g =
          _mm256_i32gather_epi32(base, _mm256_add_epi32(_mm256_mullo_epi32(iy, vpstride), _mm256_add_epi32(ix, ix)), 1);
      uint8_t* o = out + j * ostride + i;
      if (nu - i >= 8) {
        GrayCombineAvx2(fx, fy, _mm256_shuffle_epi8(g, top), _mm256_shuffle_epi8(g, bottom), o);
      } else {
        uint8_t tail[8];
        GrayCombineAvx2(fx, fy, _mm256_shuffle_epi8(g, top), _mm256_shuffle_epi8(g, bottom), tail);
        std::memcpy(o, tail, size_t(nu - i));
      }
    }
  }
}

// Bayer: a pixel's taps are rows ra .. ra + 3 and columns start .. start + 3 (ra = (((y >> 1) + 1/128 grid px) >>
// 15) - 1, start alike), so two 8-byte words of the patch (pair rows ra - r0 and ra - r0 + 2) instead of the
// four that BayerRgbRowAvx2 reads from the mosaic. A region reaching a row's last 3 bytes goes row by row too.
__attribute__((target("avx2"), flatten)) void BayerRgbTileAvx2(const uint8_t* src, ptrdiff_t stride, const Tile& t,
                                                               int T, int nu, int nv, uint8_t* out, ptrdiff_t ostride) {
  TilePassAvx2 p;
  p.Coordinates(t, T, nu, nv);
  // Taps start at cell - 1, cell = ((v >> 1) + kHalf) >> 15 (non-decreasing in v).
  const auto cell = [](int32_t q) { return ((q >> 1) + kHalf) >> 15; };
  const int c0 = cell(p.x0) - 1, c1 = cell(p.x1) + 2, r0 = cell(p.y0) - 1, r1 = cell(p.y1) + 2;  // columns, rows read
  const int columns = c1 - c0 + 1, pairs = r1 - r0;
  if (c1 > stride - 1 || columns > TilePassAvx2::kColumns || pairs > TilePassAvx2::kPairs) {
    for (int j = 0; j < nv; ++j) BayerRgbRowAvx2(src, stride, p.Row(j), 0, nu, out + j * ostride);
    return;
  }
  const ptrdiff_t pstride = p.CopyPairs(src, stride, r0, pairs, c0, columns);
  const __m256i origin_c = _mm256_set1_epi32(c0 + 1), origin_r = _mm256_set1_epi32(r0 + 1),
                bit15 = _mm256_set1_epi32(0x8000);
  const __m256i vpstride = _mm256_set1_epi32(static_cast<int>(pstride));
  const auto load = [](const uint8_t* q) {
    long long w;
    std::memcpy(&w, q, 8);
    return w;
  };
  p.PixelSteps(
      nu, nv,
      [&](int j, int i) __attribute__((target("avx2"))) {
        const __m256i half = _mm256_set1_epi32(kHalf);
        const __m256i pxe = _mm256_add_epi32(_mm256_srai_epi32(p.X(j, i), 1), half);
        const __m256i pye = _mm256_add_epi32(_mm256_srai_epi32(p.Y(j, i), 1), half);
        const __m256i col = _mm256_sub_epi32(_mm256_srai_epi32(pxe, 15), origin_c);   // start - c0
        const __m256i prow = _mm256_sub_epi32(_mm256_srai_epi32(pye, 15), origin_r);  // ra - r0
        return _mm256_add_epi32(_mm256_mullo_epi32(prow, vpstride), _mm256_add_epi32(col, col));
      },
      [&](const int32_t* off, int j, int i) __attribute__((target("avx2"))) {
        const BayerGrids8 g = BayerGridsAt8(p.X(j, i), p.Y(j, i));
        const __m256i &pxe = g.pxe, &pye = g.pye;
        // (ce, ce + 2, co, co + 2) as byte 2 c + s of a pixel's word: columns (1, 3, 0, 2) or (0, 2, 1, 3) from
        // start (as the AVX-512 Bayer16), row s = 1 for the even grids when pye's bit 15 is clear, else 0.
        const __m256i xodd = _mm256_cmpeq_epi32(_mm256_and_si256(pxe, bit15), bit15);
        const __m256i yodd = _mm256_cmpeq_epi32(_mm256_and_si256(pye, bit15), bit15);
        const __m256i cols = _mm256_blendv_epi8(_mm256_set1_epi32(0x04000602), _mm256_set1_epi32(0x06020400), xodd);
        const __m256i idx_e = _mm256_add_epi8(cols, _mm256_andnot_si256(yodd, _mm256_set1_epi32(0x01010101)));
        const __m256i idx_o = _mm256_xor_si256(idx_e, _mm256_set1_epi32(0x01010101));
        __m256i eA, eB, oA, oB;
        PairShuffles(idx_e, &eA, &eB);
        PairShuffles(idx_o, &oA, &oB);
        const uint8_t* q = p.patch;
        const uint8_t* qb = p.patch + 2 * pstride;
        const __m256i tA = _mm256_setr_epi64x(load(q + off[0]), load(q + off[1]), load(q + off[4]), load(q + off[5]));
        const __m256i tB = _mm256_setr_epi64x(load(q + off[2]), load(q + off[3]), load(q + off[6]), load(q + off[7]));
        const __m256i bA =
            _mm256_setr_epi64x(load(qb + off[0]), load(qb + off[1]), load(qb + off[4]), load(qb + off[5]));
        const __m256i bB =
            _mm256_setr_epi64x(load(qb + off[2]), load(qb + off[3]), load(qb + off[6]), load(qb + off[7]));
        const __m256i et = _mm256_unpacklo_epi64(_mm256_shuffle_epi8(tA, eA), _mm256_shuffle_epi8(tB, eB));
        const __m256i ot = _mm256_unpacklo_epi64(_mm256_shuffle_epi8(tA, oA), _mm256_shuffle_epi8(tB, oB));
        const __m256i eb = _mm256_unpacklo_epi64(_mm256_shuffle_epi8(bA, eA), _mm256_shuffle_epi8(bB, eB));
        const __m256i ob = _mm256_unpacklo_epi64(_mm256_shuffle_epi8(bA, oA), _mm256_shuffle_epi8(bB, oB));
        uint8_t* o = out + j * ostride + 3 * i;
        if (nu - i >= 8) {
          BayerCombineAvx2(g.fxe, g.fxo, g.fye, g.fyo, et, eb, ot, ob, o);
        } else {
          uint8_t tail[24];
          BayerCombineAvx2(g.fxe, g.fxo, g.fye, g.fyo, et, eb, ot, ob, tail);
          std::memcpy(o, tail, size_t(3 * (nu - i)));
        }
      });
}
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
