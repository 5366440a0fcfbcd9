#include "raytrace/sampling.h"

#include <cmath>
#include <cstddef>

#include "core/sincos.h"
#include "core/vector_clones.h"

namespace hovs::raytrace {
namespace {

// True where the x86-64-v4 copies of the functions below (picked by hand, not by target_clones) can run.
bool CpuHasX86_64V4() {
#if defined(HOVS_VECTOR_CLONES_ENABLED)
  static const bool v4 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
                         __builtin_cpu_supports("avx512cd");
  return v4;
#else
  return false;
#endif
}

// SplitMix64, always inlined (the vectorised loops below call it: helpers of target-specific functions must be).
__attribute__((always_inline)) inline uint64_t SplitMixInline(uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
// Uniform(h): q = h >> 11 < 2^53 as a double, exactly: kDirect, by the 64-bit integer conversion (AVX-512DQ),
// else its low 52 bits as the mantissa of 2^52 + q_low, minus 2^52, plus the top bit's 2^52 (all exact).
template <bool kDirect>
__attribute__((always_inline)) inline double UniformOf(uint64_t h) {
  const uint64_t q = h >> 11;
  if (kDirect) return static_cast<double>(static_cast<int64_t>(q)) * (1.0 / 9007199254740992.0);
  double low;
  const uint64_t bits = 0x4330000000000000ull | (q & 0xFFFFFFFFFFFFFull);
  __builtin_memcpy(&low, &bits, sizeof low);
  return ((low - 4503599627370496.0) + static_cast<double>(static_cast<int>(q >> 52)) * 4503599627370496.0) *
         (1.0 / 9007199254740992.0);
}

// The jittered image positions of a chunk's samples: samples s_begin .. s_end - 1 of P pixels, sample s of pixel q
// at k = (s - s_begin) P + q. It has the hash key pixel[q] * 4096 + s, lies in the pixel with centre (x[q], y[q])
// and, when stratified, in the stratum (s % grid, s / grid) of a grid of grid x grid strata (inv_grid = 1 /
// grid). The same arithmetic as SplitMix and Uniform above, vectorised over the pixels. The 53-bit integer
// becomes a double exactly, as the conversion in Uniform: kDirect, by the 64-bit integer conversion (an AVX-512DQ
// instruction; without it GCC does not vectorise the loop), else through its bits (the same value).
template <bool kDirect>
__attribute__((always_inline)) inline void JitteredSamplesOf(int P, int s_begin, int s_end, int grid, uint64_t seed_mix,
                                                             bool stratified, double inv_grid,
                                                             const int* __restrict pixel, const int* __restrict x,
                                                             const int* __restrict y, double* __restrict u,
                                                             double* __restrict v) {
  const double g = stratified ? 1.0 : 0.0, scale = stratified ? inv_grid : 1.0;
  for (int smp = s_begin; smp < s_end; ++smp) {
    const double gsx = g * (smp % grid), gsy = g * (smp / grid);
    double* __restrict us = u + static_cast<ptrdiff_t>(smp - s_begin) * P;
    double* __restrict vs = v + static_cast<ptrdiff_t>(smp - s_begin) * P;
    for (int q = 0; q < P; ++q) {
      const uint64_t key = static_cast<uint64_t>(pixel[q]) * 4096 + static_cast<uint64_t>(smp);
      const uint64_t h = SplitMixInline(seed_mix ^ key);
      const double ju = UniformOf<kDirect>(h), jv = UniformOf<kDirect>(SplitMixInline(h));
      us[q] = static_cast<double>(x[q]) + ((gsx + ju) * scale - 0.5);
      vs[q] = static_cast<double>(y[q]) + ((gsy + jv) * scale - 0.5);
    }
  }
}

HOVS_VECTOR_CLONES
void JitteredSamplesBits(int P, int s_begin, int s_end, int grid, uint64_t seed_mix, bool stratified, double inv_grid,
                         const int* __restrict pixel, const int* __restrict x, const int* __restrict y,
                         double* __restrict u, double* __restrict v) {
  JitteredSamplesOf<false>(P, s_begin, s_end, grid, seed_mix, stratified, inv_grid, pixel, x, y, u, v);
}

#if defined(HOVS_VECTOR_CLONES_ENABLED)
__attribute__((target("arch=x86-64-v4"))) void JitteredSamplesDirect(int P, int s_begin, int s_end, int grid,
                                                                     uint64_t seed_mix, bool stratified,
                                                                     double inv_grid, const int* __restrict pixel,
                                                                     const int* __restrict x, const int* __restrict y,
                                                                     double* __restrict u, double* __restrict v) {
  JitteredSamplesOf<true>(P, s_begin, s_end, grid, seed_mix, stratified, inv_grid, pixel, x, y, u, v);
}
#endif

}  // namespace

uint64_t SplitMix(uint64_t x) { return SplitMixInline(x); }

void JitteredSamples(int P, int s_begin, int s_end, int grid, uint64_t seed_mix, bool stratified, double inv_grid,
                     const int* pixel, const int* x, const int* y, double* u, double* v) {
#if defined(HOVS_VECTOR_CLONES_ENABLED)
  if (CpuHasX86_64V4()) {
    JitteredSamplesDirect(P, s_begin, s_end, grid, seed_mix, stratified, inv_grid, pixel, x, y, u, v);
    return;
  }
#endif
  JitteredSamplesBits(P, s_begin, s_end, grid, seed_mix, stratified, inv_grid, pixel, x, y, u, v);
}

namespace {

// The thin-lens aperture points and exposure times of a chunk's samples (laid out as JitteredSamples'): sample
// smp of pixel q has the key pixel[q] * 4096 + smp and the hash h2 = SplitMix(SplitMix(seed_mix ^ key) ^
// 0xD1B54A32D192ED03); its aperture point is uniform on the unit disc, radius sqrt(Uniform(h2)) at
// Uniform(SplitMix(h2)) turns (0 without a lens), its time exposure * Uniform(SplitMix(h2 ^ 0x9E3779B97F4A7C15))
// (0 without blur). Vectorised: the angle's sine and cosine from core/sincos.h.
template <bool kDirect>
__attribute__((always_inline)) inline void LensSamplesOf(int P, int s_begin, int s_end, uint64_t seed_mix, bool lens,
                                                         double exposure, const int* __restrict pixel,
                                                         double* __restrict disc_x, double* __restrict disc_y,
                                                         double* __restrict tau) {
  const double on = lens ? 1.0 : 0.0;
  for (int smp = s_begin; smp < s_end; ++smp) {
    const ptrdiff_t k0 = static_cast<ptrdiff_t>(smp - s_begin) * P;
    for (int q = 0; q < P; ++q) {
      const uint64_t key = static_cast<uint64_t>(pixel[q]) * 4096 + static_cast<uint64_t>(smp);
      const uint64_t h2 = SplitMixInline(SplitMixInline(seed_mix ^ key) ^ 0xD1B54A32D192ED03ull);
      const double rr = std::sqrt(UniformOf<kDirect>(h2)) * on;
      double sn, cs;
      SinCosOfTurns(UniformOf<kDirect>(SplitMixInline(h2)), &sn, &cs);
      disc_x[k0 + q] = rr * cs, disc_y[k0 + q] = rr * sn;
      tau[k0 + q] = exposure * UniformOf<kDirect>(SplitMixInline(h2 ^ 0x9E3779B97F4A7C15ull));
    }
  }
}

HOVS_VECTOR_CLONES
void LensSamplesBits(int P, int s_begin, int s_end, uint64_t seed_mix, bool lens, double exposure,
                     const int* __restrict pixel, double* __restrict disc_x, double* __restrict disc_y,
                     double* __restrict tau) {
  LensSamplesOf<false>(P, s_begin, s_end, seed_mix, lens, exposure, pixel, disc_x, disc_y, tau);
}

#if defined(HOVS_VECTOR_CLONES_ENABLED)
__attribute__((target("arch=x86-64-v4"))) void LensSamplesDirect(int P, int s_begin, int s_end, uint64_t seed_mix,
                                                                 bool lens, double exposure,
                                                                 const int* __restrict pixel, double* __restrict disc_x,
                                                                 double* __restrict disc_y, double* __restrict tau) {
  LensSamplesOf<true>(P, s_begin, s_end, seed_mix, lens, exposure, pixel, disc_x, disc_y, tau);
}
#endif

}  // namespace

void LensSamples(int P, int s_begin, int s_end, uint64_t seed_mix, bool lens, double exposure, const int* pixel,
                 double* disc_x, double* disc_y, double* tau) {
#if defined(HOVS_VECTOR_CLONES_ENABLED)
  if (CpuHasX86_64V4()) {
    LensSamplesDirect(P, s_begin, s_end, seed_mix, lens, exposure, pixel, disc_x, disc_y, tau);
    return;
  }
#endif
  LensSamplesBits(P, s_begin, s_end, seed_mix, lens, exposure, pixel, disc_x, disc_y, tau);
}

}  // namespace hovs::raytrace
