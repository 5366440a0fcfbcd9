// Sine and cosine of an angle given in turns (w turns = 2 pi w radians) from additions and multiplications only:
// the same bits on every CPU, compiler and libm (std::sin and std::cos come from the C library, whose results
// may change between its versions), and a loop of them vectorises (HOVS_VECTOR_CLONES functions may call it,
// core/vector_clones.h). The renderer's thin-lens samples use it.
//
// Method: w is reduced to the nearest quarter turn q / 4 and a remainder f in [-1/8, 1/8] turn (|theta| <= pi / 4);
// sin and cos of theta by their Taylor series to degree 17 and 16 (truncation below 5e-18), then rotated by q
// quarter turns. Valid domain: |w| < 2^28 (the quarter count fits an int32 and the reduction is exact). Error:
// within 3e-16 of the true values. Files that call it in a loop compile with -ffp-contract=off, as those of
// HOVS_VECTOR_CLONES functions do (a fused multiply-add would change the bits on CPUs that have it).
#pragma once

#include <cstdint>

namespace hovs {

__attribute__((always_inline)) inline void SinCosOfTurns(double w, double* s, double* c) {
  const double x = 4.0 * w;  // quarter turns (exact: a power of two)
  // The nearest whole quarter q: floor(x + 0.5) as a truncation and a compare, which vectorise.
  const double xr = x + 0.5;
  const int32_t t = static_cast<int32_t>(xr);
  const int32_t q = static_cast<double>(t) > xr ? t - 1 : t;
  const double f = x - static_cast<double>(q);  // in [-0.5, 0.5] quarter turns, exact
  const double th = f * 1.5707963267948966;     // radians, |th| <= pi / 4
  const double th2 = th * th;
  // sin th = th + th th2 (-1/3! + th2 (1/5! - ...)) to 1/17!, cos th = 1 + th2 (-1/2! + th2 (1/4! - ...)) to
  // 1/16!, both in Horner form from the highest term.
  constexpr double kSin[8] = {2.8114572543455207632e-15,  -7.6471637318198164759e-13, 1.6059043836821614599e-10,
                              -2.5052108385441718775e-08, 2.7557319223985890653e-06,  -1.9841269841269841270e-04,
                              8.3333333333333333333e-03,  -1.6666666666666666667e-01};
  constexpr double kCos[8] = {
      4.7794773323873852974e-14, -1.1470745597729724714e-11, 2.0876756987868098979e-09, -2.7557319223985890653e-07,
      2.4801587301587301587e-05, -1.3888888888888888889e-03, 4.1666666666666666667e-02, -0.5};
  double ps = kSin[0], pc = kCos[0];
  for (int j = 1; j < 8; ++j) ps = ps * th2 + kSin[j], pc = pc * th2 + kCos[j];
  const double sn = th + th * (th2 * ps);
  const double cs = 1.0 + th2 * pc;
  // (sin, cos) of th + q pi / 2.
  const int32_t k = q & 3;
  const double s1 = k == 0 ? sn : (k == 1 ? cs : (k == 2 ? -sn : -cs));
  const double c1 = k == 0 ? cs : (k == 1 ? -sn : (k == 2 ? -cs : sn));
  *s = s1, *c = c1;
}

}  // namespace hovs
