// Row kernels of the fast remap (internal to unwrap/). Coordinates are 16.16 fixed point at the sampled level;
// bilinear weights are 6-bit (positions rounded to 1/64 px), the same arithmetic in the scalar and the AVX2
// versions, so their outputs are bit-identical. The caller guarantees every tap lies inside the image
// (interior tiles). The AVX2 versions are chosen at run time when the CPU has AVX2.
#pragma once

#include <cstddef>
#include <cstdint>

#include "unwrap/remap_table.h"

namespace hovs::unwrap::kernels {

bool HaveAvx2();

// The coordinates of a row: per-pixel arrays (dense tiles) or the row polynomial of an interp tile.
struct RowCoords {
  const int32_t* xs = nullptr;   // null: use poly
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

// Scalar versions (also used for tails and tests).
void BilinearRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                          uint8_t* out);
void BilinearGrayRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                           uint8_t* out);
void BayerRgbRowScalar(const uint8_t* src, ptrdiff_t stride, const RowCoords& c, int i0, int n,
                       uint8_t* out);

}  // namespace hovs::unwrap::kernels
