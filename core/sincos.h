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
  const double x = 4.0 * w;   // quarter turns (exact: a power of two)
  // The nearest whole quarter q: floor(x + 0.5) as a truncation and a compare, which vectorise.
  const double xr = x + 0.5;
  const int32_t t = static_cast<int32_t>(xr);
  const int32_t q = static_cast<double>(t) > xr ? t - 1 : t;
  const double f = x - static_cast<double>(q);   // in [-0.5, 0.5] quarter turns, exact
  const double th = f * 1.5707963267948966;      // radians, |th| <= pi / 4
  const double th2 = th * th;
  // sin th = th + th th2 (-1/3! + th2 (1/5! - th2 (1/7! - ...))) to 1/17!, in Horner form.
  double ps = 2.8114572543455207632e-15;   //  1/17!
  ps = ps * th2 - 7.6471637318198164759e-13;   // -1/15!
  ps = ps * th2 + 1.6059043836821614599e-10;   //  1/13!
  ps = ps * th2 - 2.5052108385441718775e-08;   // -1/11!
  ps = ps * th2 + 2.7557319223985890653e-06;   //  1/9!
  ps = ps * th2 - 1.9841269841269841270e-04;   // -1/7!
  ps = ps * th2 + 8.3333333333333333333e-03;   //  1/5!
  ps = ps * th2 - 1.6666666666666666667e-01;   // -1/3!
  const double sn = th + th * (th2 * ps);
  // cos th = 1 + th2 (-1/2! + th2 (1/4! - ...)) to 1/16!.
  double pc = 4.7794773323873852974e-14;   //  1/16!
  pc = pc * th2 - 1.1470745597729724714e-11;   // -1/14!
  pc = pc * th2 + 2.0876756987868098979e-09;   //  1/12!
  pc = pc * th2 - 2.7557319223985890653e-07;   // -1/10!
  pc = pc * th2 + 2.4801587301587301587e-05;   //  1/8!
  pc = pc * th2 - 1.3888888888888888889e-03;   // -1/6!
  pc = pc * th2 + 4.1666666666666666667e-02;   //  1/4!
  pc = pc * th2 - 0.5;                         // -1/2!
  const double cs = 1.0 + th2 * pc;
  // (sin, cos) of th + q pi / 2.
  const int32_t k = q & 3;
  const double s1 = k == 0 ? sn : (k == 1 ? cs : (k == 2 ? -sn : -cs));
  const double c1 = k == 0 ? cs : (k == 1 ? -sn : (k == 2 ? -cs : sn));
  *s = s1, *c = c1;
}

}  // namespace hovs
