// Where a pixel's samples fall: the seeded, stratified jitter of their image positions and, for a thin lens and
// motion blur, their aperture points and times. Every value is a hash of (seed, pixel, sample), so a frame is the
// same whatever the threads do, and each function has a vectorised copy that gives the same bits.
#pragma once

#include <cstdint>

namespace hovs::raytrace {

// SplitMix64's mixing function.
uint64_t SplitMix(uint64_t x);

// The jittered image positions of a chunk's samples: samples s_begin .. s_end - 1 of P pixels, sample s of pixel q
// at k = (s - s_begin) P + q, in the pixel with centre (x[q], y[q]) (stratified: in the stratum (s % grid, s / grid)
// of grid x grid strata; inv_grid = 1 / grid). pixel[q]: the pixel's index in the frame (the hash key).
void JitteredSamples(int P, int s_begin, int s_end, int grid, uint64_t seed_mix, bool stratified, double inv_grid,
                     const int* pixel, const int* x, const int* y, double* u, double* v);

// The thin-lens aperture points (uniform on the unit disc; 0 without a lens) and exposure times (in [0, exposure])
// of a chunk's samples, laid out as JitteredSamples'.
void LensSamples(int P, int s_begin, int s_end, uint64_t seed_mix, bool lens, double exposure, const int* pixel,
                 double* disc_x, double* disc_y, double* tau);

}  // namespace hovs::raytrace
