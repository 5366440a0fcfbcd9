// AVX-512 versions of the remap kernels (AVX-512 F, BW, VL, DQ and VBMI: Intel Ice Lake and later, AMD Zen 4 and
// later), 16 output pixels per step. The arithmetic is the scalar kernels' (remap_kernels.h), so the outputs are
// bit-identical to theirs; this file is compiled with -ffp-contract=off so the row polynomial's multiply and add
// are never fused.
//
// What differs from the AVX2 kernels is mostly the reading. Interp tiles (nearly all of a view) first copy the
// source region their pixels read into a small patch that stays in L1 (see BilinearRgbTile below; the AVX2 tiles
// do the same, remap_kernels.cc): RGB as it is, grey and Bayer with two source rows interleaved
// byte by byte, so that a grey pixel's four taps are one 4-byte word (one 16-lane gather per 16 pixels) and a
// Bayer pixel's sixteen taps two 8-byte words (plain loads, two per 128-bit lane, put in order by two-source byte
// permutations) instead of four gathers from the mosaic. An RGB pixel reads one 8-byte word per source row (its
// left and right taps), also by plain loads. The row kernels (Row16 below; dense tiles and regions too large for
// a patch) read the frame itself: grey and Bayer by 16-lane gathers, RGB by the same plain loads. The 16 pixels
// are put into their output order by one byte permutation (VBMI) and written with two plain stores. Row tails run
// the same 16-lane code with the lanes past the row's end given lane 0's coordinates and a masked store.
#include <immintrin.h>

#include "unwrap/remap_kernels.h"

// GCC 12's AVX-512 headers start many intrinsics from _mm512_undefined_*(), which -Wmaybe-uninitialized reports
// at every inlined use (a known false alarm of the headers, not of this file; -Wuninitialized for the same from
// _mm512_reduce_*).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

#define HOVS_AVX512 __attribute__((target("avx512f,avx512bw,avx512vl,avx512dq,avx512vbmi")))

namespace hovs::unwrap::kernels::avx512 {
namespace {

constexpr int32_t kHalf = 1 << 9;  // as remap_kernels.cc: positions rounded to the nearest 1/64 px

// Coordinates of pixels i .. i + 15 of a row (the row polynomial in RowPoly::X's float operations). Lanes at or
// past `n` (n < 16 for a tail) repeat lane 0, so every lane reads inside the image.
HOVS_AVX512 inline void Coords16(const RowCoords& c, int i, int n, __m512i* x, __m512i* y) {
  const __mmask16 live = n >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << n) - 1);
  if (c.xs) {
    *x = _mm512_maskz_loadu_epi32(live, c.xs + i);
    *y = _mm512_maskz_loadu_epi32(live, c.ys + i);
  } else {
    const __m512 fi = _mm512_cvtepi32_ps(_mm512_add_epi32(
        _mm512_set1_epi32(i), _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)));
    const __m512i one = _mm512_set1_epi32(65536);
    const RowPoly& p = c.poly;
    const __m512 px = _mm512_add_ps(
        _mm512_set1_ps(p.bx),
        _mm512_mul_ps(fi, _mm512_add_ps(_mm512_set1_ps(p.c1x), _mm512_mul_ps(fi, _mm512_set1_ps(p.c2x)))));
    const __m512 py = _mm512_add_ps(
        _mm512_set1_ps(p.by),
        _mm512_mul_ps(fi, _mm512_add_ps(_mm512_set1_ps(p.c1y), _mm512_mul_ps(fi, _mm512_set1_ps(p.c2y)))));
    *x = _mm512_sub_epi32(_mm512_cvttps_epi32(px), one);
    *y = _mm512_sub_epi32(_mm512_cvttps_epi32(py), one);
  }
  if (n < 16) {
    const __m512i zero = _mm512_setzero_si512();
    *x = _mm512_mask_blend_epi32(live, _mm512_permutexvar_epi32(zero, *x), *x);
    *y = _mm512_mask_blend_epi32(live, _mm512_permutexvar_epi32(zero, *y), *y);
  }
}

// Stores the first `bytes` (<= 48) bytes of v: two plain stores for a whole step, a masked store for a tail.
HOVS_AVX512 inline void Store48(__m512i v, int bytes, uint8_t* o) {
  if (bytes == 48) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(o), _mm512_castsi512_si256(v));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(o + 32), _mm512_extracti32x4_epi32(v, 2));
  } else {
    _mm512_mask_storeu_epi8(o, (__mmask64(1) << bytes) - 1, v);
  }
}

// Per 128-bit lane, the bytes of each 64-bit word's low 16 bits repeated four times.
HOVS_AVX512 inline __m512i RepeatLowWord(__m512i v) {
  const __m512i rep = _mm512_broadcast_i32x4(_mm_setr_epi8(0, 1, 0, 1, 0, 1, 0, 1, 8, 9, 8, 9, 8, 9, 8, 9));
  return _mm512_shuffle_epi8(v, rep);
}

// The 8 x 32-bit lanes of a 256-bit half, each widened to a 64-bit word (high half zero).
HOVS_AVX512 inline __m512i Widen(__m512i v, int half) {
  return _mm512_cvtepu32_epi64(half == 0 ? _mm512_castsi512_si256(v) : _mm512_extracti64x4_epi64(v, 1));
}

// The 8-byte words at base + offs[0..7], by plain loads (two per 128-bit lane).
HOVS_AVX512 inline __m128i TwoWords(const uint8_t* base, const int32_t* offs) {
  const __m128i lo = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + offs[0]));
  return _mm_castpd_si128(_mm_loadh_pd(_mm_castsi128_pd(lo), reinterpret_cast<const double*>(base + offs[1])));
}
HOVS_AVX512 inline __m512i EightWords(const uint8_t* base, const int32_t* offs) {
  __m512i w = _mm512_castsi128_si512(TwoWords(base, offs));
  w = _mm512_inserti32x4(w, TwoWords(base, offs + 2), 1);
  w = _mm512_inserti32x4(w, TwoWords(base, offs + 4), 2);
  return _mm512_inserti32x4(w, TwoWords(base, offs + 6), 3);
}

// The byte offsets of 16 RGB pixels' top-left taps at 16.16 coordinates (x, y) in an image of row stride `stride`.
HOVS_AVX512 inline __m512i RgbOffsets(ptrdiff_t stride, __m512i x, __m512i y) {
  const __m512i ix = _mm512_srai_epi32(_mm512_add_epi32(x, _mm512_set1_epi32(kHalf)), 16);
  const __m512i iy = _mm512_srai_epi32(_mm512_add_epi32(y, _mm512_set1_epi32(kHalf)), 16);
  return _mm512_add_epi32(_mm512_mullo_epi32(iy, _mm512_set1_epi32(static_cast<int>(stride))),
                          _mm512_add_epi32(ix, _mm512_add_epi32(ix, ix)));
}

// 16 RGB pixels (bilinear) at 16.16 coordinates (x, y) whose tap offsets (RgbOffsets) are at offs; the first
// `count` are stored at o.
HOVS_AVX512 inline void RgbAt(const uint8_t* data, ptrdiff_t stride, const int32_t* offs, __m512i x, __m512i y,
                              int count, uint8_t* o) {
  const __m512i m63 = _mm512_set1_epi32(63), c64 = _mm512_set1_epi32(64);
  x = _mm512_add_epi32(x, _mm512_set1_epi32(kHalf));
  y = _mm512_add_epi32(y, _mm512_set1_epi32(kHalf));
  const __m512i fx = _mm512_and_si512(_mm512_srai_epi32(x, 10), m63);
  const __m512i fy = _mm512_and_si512(_mm512_srai_epi32(y, 10), m63);
  const __m512i wxd = _mm512_or_si512(_mm512_slli_epi32(fx, 8), _mm512_sub_epi32(c64, fx));
  const __m512i wyd = _mm512_slli_epi32(fy, 9);
  // (left, right) byte pairs of R, G, B in each pixel's 8-byte word.
  const __m512i pairs = _mm512_broadcast_i32x4(_mm_setr_epi8(0, 3, 1, 4, 2, 5, -1, -1, 8, 11, 9, 12, 10, 13, -1, -1));
  const __m512i round = _mm512_set1_epi16(32);
  __m512i v[2];
  for (int h = 0; h < 2; ++h) {
    const __m512i top = EightWords(data, offs + 8 * h), bot = EightWords(data + stride, offs + 8 * h);
    const __m512i wx = RepeatLowWord(Widen(wxd, h)), wy = RepeatLowWord(Widen(wyd, h));
    const __m512i ht = _mm512_maddubs_epi16(_mm512_shuffle_epi8(top, pairs), wx);
    const __m512i hb = _mm512_maddubs_epi16(_mm512_shuffle_epi8(bot, pairs), wx);
    const __m512i vv = _mm512_add_epi16(ht, _mm512_mulhrs_epi16(_mm512_sub_epi16(hb, ht), wy));
    v[h] = _mm512_srli_epi16(_mm512_add_epi16(vv, round), 6);
  }
  // Lane k of the pack: pixels 2k, 2k + 1 (first half) and 8 + 2k, 9 + 2k (second half), 4 bytes each (R G B 0).
  const __m512i packed = _mm512_packus_epi16(v[0], v[1]);
  alignas(64) static const uint8_t kOrder[64] = {0,  1,  2,  4,  5,  6,  16, 17, 18, 20, 21, 22, 32, 33, 34, 36,
                                                 37, 38, 48, 49, 50, 52, 53, 54, 8,  9,  10, 12, 13, 14, 24, 25,
                                                 26, 28, 29, 30, 40, 41, 42, 44, 45, 46, 56, 57, 58, 60, 61, 62,
                                                 0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0};
  Store48(_mm512_permutexvar_epi8(_mm512_load_si512(kOrder), packed), 3 * count, o);
}

// 16 RGB pixels (bilinear) at 16.16 coordinates (x, y); the first `count` are stored at o.
HOVS_AVX512 inline bool Rgb16(const uint8_t* data, ptrdiff_t stride, __m512i x, __m512i y, int count, uint8_t* o) {
  alignas(64) int32_t offs[16];
  _mm512_store_si512(offs, RgbOffsets(stride, x, y));
  RgbAt(data, stride, offs, x, y, count, o);
  return true;
}

// The value of 16 grey pixels from their taps (t: top row, b: bottom row, per dword the bytes p0 p1 0 0) and
// fractions fx, fy (1/64 px); the first `count` are stored at o.
HOVS_AVX512 inline void GrayCombine(__m512i fx, __m512i fy, __m512i t, __m512i b, int count, uint8_t* o) {
  const __m512i c64 = _mm512_set1_epi32(64);
  const __m512i wx = _mm512_or_si512(_mm512_slli_epi32(fx, 8), _mm512_sub_epi32(c64, fx));
  const __m512i ht = _mm512_maddubs_epi16(t, wx), hb = _mm512_maddubs_epi16(b, wx);
  const __m512i wy = _mm512_or_si512(_mm512_slli_epi32(fy, 16), _mm512_sub_epi32(c64, fy));
  __m512i r = _mm512_madd_epi16(_mm512_or_si512(ht, _mm512_slli_epi32(hb, 16)), wy);
  r = _mm512_srli_epi32(_mm512_add_epi32(r, _mm512_set1_epi32(1 << 11)), 12);
  const __m128i bytes = _mm512_cvtepi32_epi8(r);
  if (count == 16) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(o), bytes);
  } else {
    _mm_mask_storeu_epi8(o, __mmask16((1u << count) - 1), bytes);
  }
}

// 16 grey pixels (bilinear).
HOVS_AVX512 inline bool Gray16(const uint8_t* data, ptrdiff_t stride, __m512i x, __m512i y, int count, uint8_t* o) {
  const __m512i m63 = _mm512_set1_epi32(63), low16 = _mm512_set1_epi32(0xFFFF);
  x = _mm512_add_epi32(x, _mm512_set1_epi32(kHalf));
  y = _mm512_add_epi32(y, _mm512_set1_epi32(kHalf));
  const __m512i fx = _mm512_and_si512(_mm512_srai_epi32(x, 10), m63);
  const __m512i fy = _mm512_and_si512(_mm512_srai_epi32(y, 10), m63);
  const __m512i off =
      _mm512_add_epi32(_mm512_mullo_epi32(_mm512_srai_epi32(y, 16), _mm512_set1_epi32(static_cast<int>(stride))),
                       _mm512_srai_epi32(x, 16));
  const __m512i t = _mm512_and_si512(_mm512_i32gather_epi32(off, data, 1), low16);  // p0 p1 0 0
  const __m512i b = _mm512_and_si512(_mm512_i32gather_epi32(off, data + stride, 1), low16);
  GrayCombine(fx, fy, t, b, count, o);
  return true;
}

// The colour of 16 pixels from their mosaic taps (et, eb: the even-row grids' two tap rows, ot, ob: the odd-row
// grids'; per pixel 4 bytes: the even-column grid's taps (ce, ce + 2), then the odd-column grid's (co, co + 2)),
// pxe and pye the even grids' 16.16 positions; the first `count` are stored at o.
HOVS_AVX512 inline void BayerCombine(__m512i pxe, __m512i pye, __m512i et, __m512i eb, __m512i ot, __m512i ob,
                                     int count, uint8_t* o) {
  const __m512i m63 = _mm512_set1_epi32(63), c64 = _mm512_set1_epi32(64), c32 = _mm512_set1_epi32(32);
  const __m512i lowmask = _mm512_set1_epi32(0xFFFF);
  const __m512i fxe = _mm512_and_si512(_mm512_srai_epi32(pxe, 10), m63);
  const __m512i fxo = _mm512_and_si512(_mm512_sub_epi32(fxe, c32), m63);
  const __m512i fye = _mm512_and_si512(_mm512_srai_epi32(pye, 10), m63);
  const __m512i fyo = _mm512_and_si512(_mm512_sub_epi32(fye, c32), m63);
  // Horizontal weights (64 - fxe, fxe, 64 - fxo, fxo) and vertical (fy << 9 in both words).
  const __m512i wx =
      _mm512_or_si512(_mm512_or_si512(_mm512_sub_epi32(c64, fxe), _mm512_slli_epi32(fxe, 8)),
                      _mm512_or_si512(_mm512_slli_epi32(_mm512_sub_epi32(c64, fxo), 16), _mm512_slli_epi32(fxo, 24)));
  const __m512i wye = _mm512_or_si512(_mm512_slli_epi32(fye, 9), _mm512_slli_epi32(fye, 25));
  const __m512i wyo = _mm512_or_si512(_mm512_slli_epi32(fyo, 9), _mm512_slli_epi32(fyo, 25));
  const __m512i het = _mm512_maddubs_epi16(et, wx), heb = _mm512_maddubs_epi16(eb, wx);  // (R, G1)
  const __m512i hot = _mm512_maddubs_epi16(ot, wx), hob = _mm512_maddubs_epi16(ob, wx);  // (G2, B)
  const __m512i ve = _mm512_add_epi16(het, _mm512_mulhrs_epi16(_mm512_sub_epi16(heb, het), wye));
  const __m512i vo = _mm512_add_epi16(hot, _mm512_mulhrs_epi16(_mm512_sub_epi16(hob, hot), wyo));
  const __m512i R = _mm512_srli_epi32(_mm512_add_epi32(_mm512_and_si512(ve, lowmask), _mm512_set1_epi32(32)), 6);
  const __m512i G =
      _mm512_srli_epi32(_mm512_add_epi32(_mm512_add_epi32(_mm512_srli_epi32(ve, 16), _mm512_and_si512(vo, lowmask)),
                                         _mm512_set1_epi32(64)),
                        7);
  const __m512i B = _mm512_srli_epi32(_mm512_add_epi32(_mm512_srli_epi32(vo, 16), _mm512_set1_epi32(32)), 6);
  const __m512i rgb0 = _mm512_or_si512(_mm512_or_si512(R, _mm512_slli_epi32(G, 8)), _mm512_slli_epi32(B, 16));
  alignas(64) static const uint8_t kDrop[64] = {0,  1,  2,  4,  5,  6,  8,  9,  10, 12, 13, 14, 16, 17, 18, 20,
                                                21, 22, 24, 25, 26, 28, 29, 30, 32, 33, 34, 36, 37, 38, 40, 41,
                                                42, 44, 45, 46, 48, 49, 50, 52, 53, 54, 56, 57, 58, 60, 61, 62,
                                                0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0};
  Store48(_mm512_permutexvar_epi8(_mm512_load_si512(kDrop), rgb0), 3 * count, o);
}

// 16 grey pixels as Gray16 from a pair-interleaved patch (see CopyPairPatch): a pixel's four taps are the 4 bytes
// at twice its column in its row's pair row, one gather per 16 pixels instead of two. Bit-identical to Gray16.
HOVS_AVX512 inline void PatchGray16(const uint8_t* patch, ptrdiff_t pstride, __m512i x, __m512i y, int count,
                                    uint8_t* o) {
  const __m512i m63 = _mm512_set1_epi32(63);
  x = _mm512_add_epi32(x, _mm512_set1_epi32(kHalf));
  y = _mm512_add_epi32(y, _mm512_set1_epi32(kHalf));
  const __m512i fx = _mm512_and_si512(_mm512_srai_epi32(x, 10), m63);
  const __m512i fy = _mm512_and_si512(_mm512_srai_epi32(y, 10), m63);
  const __m512i ix = _mm512_srai_epi32(x, 16);
  const __m512i off =
      _mm512_add_epi32(_mm512_mullo_epi32(_mm512_srai_epi32(y, 16), _mm512_set1_epi32(static_cast<int>(pstride))),
                       _mm512_add_epi32(ix, ix));
  const __m512i g = _mm512_i32gather_epi32(off, patch, 1);  // top left, bottom left, top right, bottom right
  // Per dword (p0, p1, 0, 0) of the top row and of the bottom row; byte indices count from the 128-bit lane.
  const __m512i lane = _mm512_broadcast_i32x4(_mm_setr_epi32(0, 0x04040404, 0x08080808, 0x0C0C0C0C));
  const __m512i t = _mm512_shuffle_epi8(g, _mm512_add_epi8(_mm512_set1_epi32(int(0x80800200u)), lane));
  const __m512i b = _mm512_shuffle_epi8(g, _mm512_add_epi8(_mm512_set1_epi32(int(0x80800301u)), lane));
  GrayCombine(fx, fy, t, b, count, o);
}

// 16 pixels of an RGGB mosaic to RGB, bilinear on each colour grid as BayerGridValue (remap_kernels.cc). In
// mosaic columns, a pixel's even-column grids (R, G2) are sampled at columns ce, ce + 2 and its odd-column grids
// (G1, B) at co, co + 2 with co = ce - 1 or ce + 1 (the odd grids sit half a grid cell from the even ones), so
// the four taps of a row lie in the 4 bytes from min(ce, co): one 32-bit gather per mosaic row, four rows
// (two of the even-row grids, two of the odd-row grids). Returns false (nothing written) when a pixel's 4-byte
// read would pass the end of its row.
HOVS_AVX512 inline bool Bayer16(const uint8_t* data, ptrdiff_t stride, __m512i x, __m512i y, int count, uint8_t* o) {
  const __m512i half = _mm512_set1_epi32(kHalf), ones = _mm512_set1_epi32(1);
  const __m512i vstride = _mm512_set1_epi32(static_cast<int>(stride));
  // Grid positions (16.16, as BayerGridValue): the odd-column grids' is pxe - 1/2 grid cell, exactly (x is
  // shifted before the halving by an even amount), so their fraction is fxe - 32 (mod 64) and their first tap
  // co is ce - 1 when pxe's fraction is below 1/2, ce + 1 otherwise: the four taps start at (pxe >> 15) - 1.
  // Rows alike.
  const __m512i pxe = _mm512_add_epi32(_mm512_srai_epi32(x, 1), half);
  const __m512i pye = _mm512_add_epi32(_mm512_srai_epi32(y, 1), half);
  const __m512i start = _mm512_sub_epi32(_mm512_srai_epi32(pxe, 15), ones);
  if (_mm512_cmpgt_epi32_mask(start, _mm512_set1_epi32(static_cast<int>(stride) - 4)) != 0) return false;
  const __m512i bit15 = _mm512_set1_epi32(0x8000);
  const __m512i rowe = _mm512_slli_epi32(_mm512_srai_epi32(pye, 16), 1);
  const __m512i offe = _mm512_add_epi32(_mm512_mullo_epi32(rowe, vstride), start);
  const __m512i offo = _mm512_mask_blend_epi32(_mm512_test_epi32_mask(pye, bit15), _mm512_sub_epi32(offe, vstride),
                                               _mm512_add_epi32(offe, vstride));
  // Byte indices (ce, ce + 2, co, co + 2) - start inside each pixel's own dword: (1, 3, 0, 2) when co = ce - 1,
  // (0, 2, 1, 3) when co = ce + 1; plus the dword's place in its 128-bit lane.
  const __m512i idx =
      _mm512_add_epi8(_mm512_mask_blend_epi32(_mm512_test_epi32_mask(pxe, bit15), _mm512_set1_epi32(0x02000301),
                                              _mm512_set1_epi32(0x03010200)),
                      _mm512_broadcast_i32x4(_mm_setr_epi32(0, 0x04040404, 0x08080808, 0x0C0C0C0C)));
  const __m512i et = _mm512_shuffle_epi8(_mm512_i32gather_epi32(offe, data, 1), idx);
  const __m512i eb = _mm512_shuffle_epi8(_mm512_i32gather_epi32(offe, data + 2 * stride, 1), idx);
  const __m512i ot = _mm512_shuffle_epi8(_mm512_i32gather_epi32(offo, data, 1), idx);
  const __m512i ob = _mm512_shuffle_epi8(_mm512_i32gather_epi32(offo, data + 2 * stride, 1), idx);
  BayerCombine(pxe, pye, et, eb, ot, ob, count, o);
  return true;
}

// 16 pixels of an RGGB mosaic to RGB as Bayer16, reading a pair-interleaved copy of the mosaic region instead of
// the mosaic: pair row k of the patch holds mosaic rows r0 + k and r0 + k + 1 byte by byte (byte 2 j + s is
// row r0 + k + s, column c0 + j), so a pixel's four tap rows (ra .. ra + 3, ra = min(even grid row, odd grid
// row)) and four tap columns (start .. start + 3) are two 8-byte words, at pair rows ra - r0 and ra - r0 + 2:
// 32 plain loads per 16 pixels instead of four 16-lane gathers (64 elements). The words' offsets in the patch
// (PatchBayerOffsets; origin: the patch's first column and row, plus one) are read from offs. Bit-identical to
// Bayer16: the same taps reach BayerCombine in the same byte order.
HOVS_AVX512 inline __m512i PatchBayerOffsets(ptrdiff_t pstride, __m512i origin_c, __m512i origin_r, __m512i x,
                                             __m512i y) {
  const __m512i half = _mm512_set1_epi32(kHalf);
  const __m512i pxe = _mm512_add_epi32(_mm512_srai_epi32(x, 1), half);
  const __m512i pye = _mm512_add_epi32(_mm512_srai_epi32(y, 1), half);
  const __m512i col = _mm512_sub_epi32(_mm512_srai_epi32(pxe, 15), origin_c);  // start - c0
  const __m512i row = _mm512_sub_epi32(_mm512_srai_epi32(pye, 15), origin_r);  // ra - r0
  return _mm512_add_epi32(_mm512_mullo_epi32(row, _mm512_set1_epi32(static_cast<int>(pstride))),
                          _mm512_add_epi32(col, col));
}
HOVS_AVX512 inline void PatchBayer16(const uint8_t* patch, ptrdiff_t pstride, const int32_t* offs, __m512i x, __m512i y,
                                     int count, uint8_t* o) {
  const __m512i half = _mm512_set1_epi32(kHalf), bit15 = _mm512_set1_epi32(0x8000);
  const __m512i pxe = _mm512_add_epi32(_mm512_srai_epi32(x, 1), half);
  const __m512i pye = _mm512_add_epi32(_mm512_srai_epi32(y, 1), half);
  const __m512i t0 = EightWords(patch, offs), b0 = EightWords(patch + 2 * pstride, offs);
  const __m512i t1 = EightWords(patch, offs + 8), b1 = EightWords(patch + 2 * pstride, offs + 8);
  // Byte k of the even grids' dword is column start + (1, 3, 0, 2)[k] (co = ce - 1) or (0, 2, 1, 3)[k]
  // (co = ce + 1), as Bayer16's idx, of the even grid's row: ra + 1 when pye's bit 15 is clear (the odd grid
  // then lies a row above), ra when it is set; the odd grids' the other row of the pair. Index 8p + 2c + s into
  // the two-register table (bit 6 picks t1 / b1).
  const __m512i cols = _mm512_mask_blend_epi32(_mm512_test_epi32_mask(pxe, bit15), _mm512_set1_epi32(0x04000602),
                                               _mm512_set1_epi32(0x06020400));
  const __m512i base =
      _mm512_setr_epi32(0, 0x08080808, 0x10101010, 0x18181818, 0x20202020, 0x28282828, 0x30303030, 0x38383838,
                        0x40404040, 0x48484848, 0x50505050, 0x58585858, 0x60606060, 0x68686868, 0x70707070, 0x78787878);
  const __m512i sel = _mm512_maskz_mov_epi32(_mm512_testn_epi32_mask(pye, bit15), _mm512_set1_epi32(0x01010101));
  const __m512i idx_e = _mm512_add_epi8(_mm512_add_epi8(base, cols), sel);
  const __m512i idx_o = _mm512_xor_si512(idx_e, _mm512_set1_epi32(0x01010101));
  BayerCombine(pxe, pye, _mm512_permutex2var_epi8(t0, idx_e, t1), _mm512_permutex2var_epi8(b0, idx_e, b1),
               _mm512_permutex2var_epi8(t0, idx_o, t1), _mm512_permutex2var_epi8(b0, idx_o, b1), count, o);
}

// Pixels i0 .. i0 + n - 1 of a row, 16 per step: Step (Rgb16, Gray16, Bayer16) writes kBytes per pixel, and
// where it cannot (Bayer16 near the row's end) the scalar kernel Fallback does those pixels.
using StepFn = bool (*)(const uint8_t*, ptrdiff_t, __m512i, __m512i, int, uint8_t*);
using RowFn = void (*)(const uint8_t*, ptrdiff_t, const RowCoords&, int, int, uint8_t*);
template <StepFn Step, int kBytes, RowFn Fallback>
HOVS_AVX512 inline void Row16(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* o) {
  for (int i = 0; i < n; i += 16) {
    const int m = n - i < 16 ? n - i : 16;
    __m512i x, y;
    Coords16(c, i0 + i, m, &x, &y);
    if (!Step(data, stride, x, y, m, o + kBytes * i)) Fallback(data, stride, c, i0 + i, m, o + kBytes * i);
  }
}

HOVS_AVX512 inline void RgbRowInline(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                                     uint8_t* o) {
  Row16<Rgb16, 3, BilinearRgbRowScalar>(data, stride, c, i0, n, o);
}
HOVS_AVX512 inline void GrayRowInline(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                                      uint8_t* o) {
  Row16<Gray16, 1, BilinearGrayRowScalar>(data, stride, c, i0, n, o);
}
HOVS_AVX512 inline void BayerRowInline(const uint8_t* data, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                                       uint8_t* o) {
  Row16<Bayer16, 3, BayerRgbRowScalar>(data, stride, c, i0, n, o);
}

}  // namespace

HOVS_AVX512 void BilinearRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  RgbRowInline(src, stride, c, i0, n, out);
}
HOVS_AVX512 void BilinearGrayRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                                 uint8_t* out) {
  GrayRowInline(src, stride, c, i0, n, out);
}
HOVS_AVX512 void BayerRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out) {
  BayerRowInline(src, stride, c, i0, n, out);
}

// Interp tiles.
// The RGB, grey and Bayer tiles in three passes: (1) every pixel's coordinates (the row polynomials 16 rows at a
// time), kept, with the source region the pixels' reads cover (only bytes the row kernels would read); (2) that
// region copied into a patch, 64-byte aligned rows (it stays in L1); (3) the pixels from the patch. Reading the
// frame directly, each 16-pixel step's loads or gathers wait on L2 and beyond (the reads follow curves across the
// frame). Measured on the article's six views (the measurement of 2026-11-23 (commit a5de1f7), Zen 4, against the
// direct kernels in interleaved runs): RGB 6.2 -> 5.1 ms, Bayer 8.5 -> 6.1 ms, grey 5.3 -> 3.6 ms; the row polynomials
// 16 at a time took another 10-25 % off each. A region larger than the patch holds goes row by row through the direct
// kernels.
namespace {

constexpr int kPatchRowBytes = 256, kPatchRows = 128;  // 32 kB

struct TilePass {
  static constexpr int kRow = 64 + 16;  // coordinates kept per tile row (T <= 64; a step may fill 16 past nu)
  alignas(64) int32_t xs[64 * kRow], ys[64 * kRow];
  alignas(64) uint8_t patch[kPatchRows * kPatchRowBytes];
  int c0 = 0, c1 = 0, r0 = 0, r1 = 0;  // the range of the source cells over the tile's pixels

  // Pass 1. Cells: the RGB kernel's tap (x + 1/2 of 1/64 px) >> 16, or for a mosaic (kBayer) the start of
  // Bayer16's taps plus one, ((x >> 1) + 1/128 grid px) >> 15 (rows alike). Lanes past nu repeat lane 0.
  template <bool kBayer>
  HOVS_AVX512 void Coordinates(const Tile& t, int T, int nu, int nv) {
    __m512i xmin = _mm512_set1_epi32(INT32_MAX), xmax = _mm512_set1_epi32(INT32_MIN), ymin = xmin, ymax = xmax;
    RowPolys<16> polys[4];  // the row polynomials 16 rows at a time (vectorised)
    for (int j0 = 0; j0 < nv; j0 += 16) InterpRowPolys(t, T, j0, &polys[j0 / 16]);
    RowCoords c;
    for (int j = 0; j < nv; ++j) {
      c.poly = polys[j / 16].Row(j % 16);
      for (int i = 0; i < nu; i += 16) {
        __m512i x, y;
        Coords16(c, i, nu - i < 16 ? nu - i : 16, &x, &y);
        _mm512_store_si512(xs + j * kRow + i, x);
        _mm512_store_si512(ys + j * kRow + i, y);
        xmin = _mm512_min_epi32(xmin, x), xmax = _mm512_max_epi32(xmax, x);
        ymin = _mm512_min_epi32(ymin, y), ymax = _mm512_max_epi32(ymax, y);
      }
    }
    // The cells are non-decreasing in the coordinates: the cells of the extreme coordinates are the extreme cells.
    const auto cell = [](int32_t v) { return kBayer ? ((v >> 1) + kHalf) >> 15 : (v + kHalf) >> 16; };
    c0 = cell(_mm512_reduce_min_epi32(xmin)), c1 = cell(_mm512_reduce_max_epi32(xmax));
    r0 = cell(_mm512_reduce_min_epi32(ymin)), r1 = cell(_mm512_reduce_max_epi32(ymax));
  }
  // Pass 3 of the RGB and Bayer tiles: step(offs, j, i) for the 16 pixels from (i, j), where offs holds the 16
  // patch offsets offsets(j, i) of their words. The offsets of a tile row are computed and stored one row ahead
  // of their use, so the steps' scalar loads of them read L1, never a store still in flight: stored just before
  // (or taken out of the register, GCC's choice when it sees both) they waited on store-to-load forwarding from
  // a 64-byte store, which held back every step's loads. The measurement of 2026-12-02 (commit 1010873), one core,
  // three interleaved rounds each: Bayer 7.2-7.4 -> 5.5-5.9 ms, RGB 8.6-8.7 -> 7.3-8.2 ms for the six views
  // (bit-identical).
  template <class Offsets, class Step>
  HOVS_AVX512 void PixelSteps(int nu, int nv, Offsets offsets, Step step) const {
    alignas(64) int32_t offs[2][kRow];
    const auto row = [&](int j) HOVS_AVX512 {
      for (int i = 0; i < nu; i += 16) _mm512_store_si512(offs[j & 1] + i, offsets(j, i));
    };
    row(0);
    for (int j = 0; j < nv; ++j) {
      if (j + 1 < nv) row(j + 1);
      for (int i = 0; i < nu; i += 16) step(offs[j & 1] + i, j, i);
    }
  }
  HOVS_AVX512 __m512i X(int j, int i) const { return _mm512_load_si512(xs + j * kRow + i); }
  HOVS_AVX512 __m512i Y(int j, int i) const { return _mm512_load_si512(ys + j * kRow + i); }
};

// Pass 2 for RGB: rows `first` .. first + rows - 1, bytes `from` .. from + bytes - 1 of each, at pstride.
HOVS_AVX512 inline void CopyPatch(const uint8_t* src, ptrdiff_t stride, int first, int rows, ptrdiff_t from, int bytes,
                                  uint8_t* patch, ptrdiff_t pstride) {
  for (int k = 0; k < rows; ++k) {
    const uint8_t* a = src + (first + k) * stride + from;
    for (int b = 0; b < bytes; b += 64) {
      const __mmask64 m = bytes - b >= 64 ? ~__mmask64(0) : (__mmask64(1) << (bytes - b)) - 1;
      _mm512_store_si512(patch + k * pstride + b, _mm512_maskz_loadu_epi8(m, a + b));
    }
  }
}

// Pass 2 for Bayer: pair row k holds mosaic rows first + k and first + k + 1 byte by byte (byte 2 j + s: row
// first + k + s, column from + j), columns from .. from + columns - 1 (see PatchBayer16).
HOVS_AVX512 inline void CopyPairPatch(const uint8_t* src, ptrdiff_t stride, int first, int pairs, ptrdiff_t from,
                                      int columns, uint8_t* patch, ptrdiff_t pstride) {
  for (int k = 0; k < pairs; ++k) {
    const uint8_t* a = src + (first + k) * stride + from;
    for (int cc = 0; cc < columns; cc += 32) {
      const __mmask32 m = columns - cc >= 32 ? __mmask32(0xFFFFFFFFu) : __mmask32((1u << (columns - cc)) - 1);
      const __m512i top = _mm512_cvtepu8_epi16(_mm256_maskz_loadu_epi8(m, a + cc));
      const __m512i bottom = _mm512_cvtepu8_epi16(_mm256_maskz_loadu_epi8(m, a + stride + cc));
      _mm512_store_si512(patch + k * pstride + 2 * cc, _mm512_or_si512(top, _mm512_slli_epi16(bottom, 8)));
    }
  }
}

HOVS_AVX512 inline ptrdiff_t PatchStride(int bytes) { return (bytes + 63) & ~63; }

}  // namespace

// RGB: a pixel reads 8 bytes from 3 x its tap column in its tap row and the row below, so the region is columns
// c0 .. c1 + 1 (plus 2 bytes), rows r0 .. r1 + 1. Coordinates move by whole pixels only: the same weights.
HOVS_AVX512 void BilinearRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv,
                                 uint8_t* out, ptrdiff_t ostride) {
  TilePass p;
  p.Coordinates<false>(t, T, nu, nv);
  const int bytes = 3 * (p.c1 - p.c0) + 8, rows = p.r1 - p.r0 + 2;
  if (bytes > kPatchRowBytes || rows > kPatchRows) {
    for (int j = 0; j < nv; ++j)
      RgbRowInline(src, stride, RowCoords{p.xs + j * TilePass::kRow, p.ys + j * TilePass::kRow, {}}, 0, nu,
                   out + j * ostride);
    return;
  }
  const ptrdiff_t pstride = PatchStride(bytes);
  CopyPatch(src, stride, p.r0, rows, 3 * ptrdiff_t(p.c0), bytes, p.patch, pstride);
  const __m512i dx = _mm512_set1_epi32(p.c0 * 65536), dy = _mm512_set1_epi32(p.r0 * 65536);
  p.PixelSteps(
      nu, nv,
      [&](int j, int i)
          HOVS_AVX512 { return RgbOffsets(pstride, _mm512_sub_epi32(p.X(j, i), dx), _mm512_sub_epi32(p.Y(j, i), dy)); },
      [&](const int32_t* offs, int j, int i) HOVS_AVX512 {
        RgbAt(p.patch, pstride, offs, _mm512_sub_epi32(p.X(j, i), dx), _mm512_sub_epi32(p.Y(j, i), dy),
              nu - i < 16 ? nu - i : 16, out + j * ostride + 3 * i);
      });
}

// Grey: a pixel's taps are columns c .. c + 1 of rows r .. r + 1 (its cell (c, r)): pair rows r0 .. r1, columns
// c0 .. c1 + 1.
HOVS_AVX512 void BilinearGrayTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv,
                                  uint8_t* out, ptrdiff_t ostride) {
  TilePass p;
  p.Coordinates<false>(t, T, nu, nv);
  const int columns = p.c1 - p.c0 + 2, pairs = p.r1 - p.r0 + 1;
  if (2 * columns > kPatchRowBytes || pairs > kPatchRows) {
    for (int j = 0; j < nv; ++j)
      GrayRowInline(src, stride, RowCoords{p.xs + j * TilePass::kRow, p.ys + j * TilePass::kRow, {}}, 0, nu,
                    out + j * ostride);
    return;
  }
  const ptrdiff_t pstride = PatchStride(2 * columns);
  CopyPairPatch(src, stride, p.r0, pairs, p.c0, columns, p.patch, pstride);
  const __m512i dx = _mm512_set1_epi32(p.c0 * 65536), dy = _mm512_set1_epi32(p.r0 * 65536);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; i += 16)
      PatchGray16(p.patch, pstride, _mm512_sub_epi32(p.X(j, i), dx), _mm512_sub_epi32(p.Y(j, i), dy),
                  nu - i < 16 ? nu - i : 16, out + j * ostride + i);
}

// Bayer: a pixel's taps are rows ra .. ra + 3 and columns start .. start + 3 (cells minus one), so the region
// is columns c0 - 1 .. c1 + 2 and rows r0 - 1 .. r1 + 2, as pair rows r0 - 1 .. r1 + 1. One reaching a row's
// last 3 bytes (where Bayer16 hands pixels to the scalar kernel) goes row by row too.
HOVS_AVX512 void BayerRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                              ptrdiff_t ostride) {
  TilePass p;
  p.Coordinates<true>(t, T, nu, nv);
  const int columns = p.c1 - p.c0 + 4, pairs = p.r1 - p.r0 + 3;
  if (p.c1 + 2 > stride - 1 || 2 * columns > kPatchRowBytes || pairs > kPatchRows) {
    for (int j = 0; j < nv; ++j)
      BayerRowInline(src, stride, RowCoords{p.xs + j * TilePass::kRow, p.ys + j * TilePass::kRow, {}}, 0, nu,
                     out + j * ostride);
    return;
  }
  const ptrdiff_t pstride = PatchStride(2 * columns);
  CopyPairPatch(src, stride, p.r0 - 1, pairs, p.c0 - 1, columns, p.patch, pstride);
  const __m512i origin_c = _mm512_set1_epi32(p.c0), origin_r = _mm512_set1_epi32(p.r0);
  p.PixelSteps(
      nu, nv,
      [&](int j, int i) HOVS_AVX512 { return PatchBayerOffsets(pstride, origin_c, origin_r, p.X(j, i), p.Y(j, i)); },
      [&](const int32_t* offs, int j, int i) HOVS_AVX512 {
        PatchBayer16(p.patch, pstride, offs, p.X(j, i), p.Y(j, i), nu - i < 16 ? nu - i : 16,
                     out + j * ostride + 3 * i);
      });
}

}  // namespace hovs::unwrap::kernels::avx512
