// Row kernels of the fast remap (internal to unwrap/). Coordinates are 16.16 fixed point at the sampled level;
// bilinear weights are 6-bit (positions rounded to 1/64 px), the same arithmetic in the scalar and the AVX2
// versions, so their outputs are bit-identical. The caller guarantees every tap lies inside the image
// (interior tiles). The widest version the CPU runs (AVX-512, AVX2, scalar) is chosen at run time; all of them
// produce the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>

#include "unwrap/remap_table.h"

namespace hovs::unwrap::kernels {

enum class Isa : int { kScalar = 0, kAvx2 = 1, kAvx512 = 2 };
const char* ToString(Isa isa);
Isa DetectedIsa();       // the widest kernels this CPU runs (AVX-512: F, BW, VL, DQ and VBMI)
Isa ActiveIsa();         // what the dispatching functions below use: DetectedIsa(), unless limited
void LimitIsa(Isa max);  // process-wide, for tests and benchmarks: use at most this instruction set

// The coordinates of a row: per-pixel arrays (dense tiles) or the row polynomial of an interp tile.
struct RowCoords {
  const int32_t* xs = nullptr;  // null: use poly
  const int32_t* ys = nullptr;
  RowPoly poly{};
  int32_t X(int i) const { return xs ? xs[i] : poly.X(i); }
  int32_t Y(int i) const { return xs ? ys[i] : poly.Y(i); }
};

// Pixels i0 .. i0 + n - 1 of one output row; out points at pixel i0's output.
// Interleaved 8-bit RGB / grey, bilinear.
void BilinearRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
void BilinearGrayRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
// RGGB mosaic (level 0) to RGB: bilinear on each colour grid (G: mean of its two grids).
void BayerRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);

// An interp tile's nu x nv pixels (row polynomials from the tile's nodes; nu, nv <= T), written at out with
// ostride bytes per output row.
void BilinearRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                     ptrdiff_t ostride);
void BilinearGrayTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                      ptrdiff_t ostride);
void BayerRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                  ptrdiff_t ostride);

// Scalar versions (also used for tails and tests).
void BilinearRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
void BilinearGrayRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
void BayerRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);

// The AVX-512 versions (remap_kernels_avx512.cc); call only when DetectedIsa() is kAvx512.
namespace avx512 {
void BilinearRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
void BilinearGrayRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
void BayerRgbRow(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n, uint8_t* out);
void BilinearRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                     ptrdiff_t ostride);
void BilinearGrayTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                      ptrdiff_t ostride);
void BayerRgbTile(const uint8_t* src, ptrdiff_t stride, const Tile& t, int T, int nu, int nv, uint8_t* out,
                  ptrdiff_t ostride);
}  // namespace avx512

}  // namespace hovs::unwrap::kernels
