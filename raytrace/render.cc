#include "raytrace/render.h"

#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#if defined(__SSE__)
#include <immintrin.h>
#endif
#include <atomic>
#include <memory>
#include <optional>
#include <chrono>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.h"
#include "core/sincos.h"
#include "core/vector_clones.h"

namespace hovs::raytrace {

const char* const GroundTruth::kNames[GroundTruth::kChannels] = {"Z",   "P.X", "P.Y", "P.Z", "N.X", "N.Y",
                                                                 "N.Z", "id",  "mask", "M.X", "M.Y", "M.Z"};

void SensorOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(gain) && gain > 0, where + ".gain", "must be positive");
  HOVS_REQUIRE(vignetting >= 0 && vignetting < 1, where + ".vignetting", "must be in [0, 1)");
  HOVS_REQUIRE(std::isfinite(full_well) && full_well >= 0, where + ".full_well", "must be >= 0");
  HOVS_REQUIRE(std::isfinite(read_noise) && read_noise >= 0, where + ".read_noise", "must be >= 0");
  HOVS_REQUIRE(read_noise == 0 || full_well > 0, where + ".read_noise", "needs full_well > 0");
  HOVS_REQUIRE(bit_depth == 8 || bit_depth == 16, where + ".bit_depth", "must be 8 or 16 (got ", bit_depth, ")");
}

void RenderOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(samples >= 1 && samples <= 4096, where + ".samples", "must be in 1..4096 (got ", samples, ")");
  HOVS_REQUIRE(std::isfinite(lens_radius) && lens_radius >= 0 && lens_radius <= kMaxApertureRadius,
               where + ".lens_radius", "must be in [0, ", kMaxApertureRadius, "] m (got ", lens_radius, ")");
  HOVS_REQUIRE(std::isfinite(focus_distance) && focus_distance > 0, where + ".focus_distance", "must be positive");
  HOVS_REQUIRE(std::isfinite(exposure_time) && exposure_time >= 0 && exposure_time <= kMaxExposureTime,
               where + ".exposure_time", "must be in [0, ", kMaxExposureTime, "] s (got ", exposure_time, ")");
  sensor.Check(where + ".sensor");
}

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
uint64_t SplitMix(uint64_t x) { return SplitMixInline(x); }
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
__attribute__((always_inline)) inline void JitteredSamplesOf(int P, int s_begin, int s_end, int grid,
                                                             uint64_t seed_mix, bool stratified, double inv_grid,
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
__attribute__((target("arch=x86-64-v4"))) void JitteredSamplesDirect(
    int P, int s_begin, int s_end, int grid, uint64_t seed_mix, bool stratified, double inv_grid,
    const int* __restrict pixel, const int* __restrict x, const int* __restrict y, double* __restrict u,
    double* __restrict v) {
  JitteredSamplesOf<true>(P, s_begin, s_end, grid, seed_mix, stratified, inv_grid, pixel, x, y, u, v);
}
#endif

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
                                                                 const int* __restrict pixel,
                                                                 double* __restrict disc_x,
                                                                 double* __restrict disc_y, double* __restrict tau) {
  LensSamplesOf<true>(P, s_begin, s_end, seed_mix, lens, exposure, pixel, disc_x, disc_y, tau);
}
#endif

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


// What UnitRays needs of a unit, in T: the mount ring (the annulus r0 <= r <= r1 in the plane z = zr of the
// mirror frame) and the camera centre c_m there; world_from_mirror (column-major R, t) and the camera centre c_w in
// the world.
template <class T>
struct UnitRayFrame {
  T zr = 0, r0 = 0, r1 = 0, c_m[3] = {0, 0, 0}, R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0},
    c_w[3] = {0, 0, 0};
};

// A unit's batch of rays finished in one pass, from the camera rays v (mirror frame, unit length) and where
// on_mirror[i], their reflections (mirror point M, direction d in dx, dy, dz):
// - origins: tnear, from_mirror = unit on the mirror (else -1), from_camera = unit past it (else -1);
// - mount_t: for a camera ray past the mirror, where it meets the mount ring (the distance from c along v, as the
//   world ray is traced), 0 where it misses the ring; -1 on the mirror, and everywhere without ring_test;
// - the world rays: from M along d on the mirror, else from the camera centre along v, mapped by
//   world_from_mirror (d is replaced by the world direction).
// T: double, or float for single-precision colour samples. kMode: 0 any mix of rays on and past the mirror, 1
// every ray on the mirror (no ring test, v not read), 2 every ray past it (M and d not read); the same values
// in each.
template <class T, int kMode>
__attribute__((always_inline)) inline void UnitRaysOf(
    int n, const unsigned char* __restrict on_mirror, int unit, float tnear, int ring_test,
    const UnitRayFrame<T>* __restrict f, const T* __restrict vx, const T* __restrict vy, const T* __restrict vz,
    const T* __restrict Mx, const T* __restrict My, const T* __restrict Mz, T* __restrict dx, T* __restrict dy,
    T* __restrict dz, T* __restrict ox, T* __restrict oy, T* __restrict oz, float* __restrict tnear_out,
    int* __restrict from_mirror, int* __restrict from_camera, T* __restrict mount_t) {
  // Loaded once: a load inside a select stops if-conversion.
  const T r02 = f->r0 * f->r0, r12 = f->r1 * f->r1, dzr = f->zr - f->c_m[2], cx = f->c_m[0], cy = f->c_m[1];
  const T one = 1, zero = 0, half = static_cast<T>(0.5), near = static_cast<T>(1e-5);
  const T R0 = f->R[0], R1 = f->R[1], R2 = f->R[2], R3 = f->R[3], R4 = f->R[4], R5 = f->R[5], R6 = f->R[6],
          R7 = f->R[7], R8 = f->R[8], t0 = f->t[0], t1 = f->t[1], t2 = f->t[2];
  const T c0 = f->c_w[0], c1 = f->c_w[1], c2 = f->c_w[2];
  const T no_ring = ring_test ? zero : one;
  if (kMode == 1) {
    for (int i = 0; i < n; ++i) {
      tnear_out[i] = tnear;
      from_mirror[i] = unit;
      from_camera[i] = -1;
      mount_t[i] = -one;
      const T sx = dx[i], sy = dy[i], sz = dz[i];
      dx[i] = R0 * sx + R3 * sy + R6 * sz;
      dy[i] = R1 * sx + R4 * sy + R7 * sz;
      dz[i] = R2 * sx + R5 * sy + R8 * sz;
      ox[i] = R0 * Mx[i] + R3 * My[i] + R6 * Mz[i] + t0;
      oy[i] = R1 * Mx[i] + R4 * My[i] + R7 * Mz[i] + t1;
      oz[i] = R2 * Mx[i] + R5 * My[i] + R8 * Mz[i] + t2;
    }
    return;
  }
  if (kMode == 2) {
    for (int i = 0; i < n; ++i) {
      tnear_out[i] = tnear;
      from_mirror[i] = -1;
      from_camera[i] = unit;
      const T w = vz[i] != 0 ? vz[i] : one;
      const T t = dzr / w, px = cx + t * vx[i], py = cy + t * vy[i], r2 = px * px + py * py;
      const bool ring = vz[i] != 0 && t > near && r2 >= r02 && r2 <= r12;   // v is unit: t is the distance
      mount_t[i] = no_ring > half ? -one : ring ? t : zero;
      const T sx = vx[i], sy = vy[i], sz = vz[i];
      dx[i] = R0 * sx + R3 * sy + R6 * sz;
      dy[i] = R1 * sx + R4 * sy + R7 * sz;
      dz[i] = R2 * sx + R5 * sy + R8 * sz;
      ox[i] = c0, oy[i] = c1, oz[i] = c2;
    }
    return;
  }
  for (int i = 0; i < n; ++i) {
    // One comparison per select: GCC 12 if-converts these, not several selects on one bool.
    const T via = on_mirror[i] != 0 ? one : zero;
    tnear_out[i] = tnear;
    from_mirror[i] = via > half ? unit : -1;
    from_camera[i] = via > half ? -1 : unit;
    const T w = vz[i] != 0 ? vz[i] : one;
    const T t = dzr / w, px = cx + t * vx[i], py = cy + t * vy[i], r2 = px * px + py * py;
    const bool ring = vz[i] != 0 && t > near && r2 >= r02 && r2 <= r12;   // v is unit: t is the distance
    const T off = via + no_ring;   // > 0: no ring distance
    mount_t[i] = off > half ? -one : ring ? t : zero;
    const T sx = via > half ? dx[i] : vx[i], sy = via > half ? dy[i] : vy[i], sz = via > half ? dz[i] : vz[i];
    dx[i] = R0 * sx + R3 * sy + R6 * sz;
    dy[i] = R1 * sx + R4 * sy + R7 * sz;
    dz[i] = R2 * sx + R5 * sy + R8 * sz;
    const T mox = R0 * Mx[i] + R3 * My[i] + R6 * Mz[i] + t0, moy = R1 * Mx[i] + R4 * My[i] + R7 * Mz[i] + t1,
            moz = R2 * Mx[i] + R5 * My[i] + R8 * Mz[i] + t2;
    ox[i] = via > half ? mox : c0;
    oy[i] = via > half ? moy : c1;
    oz[i] = via > half ? moz : c2;
  }
}

// UnitRaysOf for a batch of which `on` rays meet the mirror.
template <class T>
HOVS_VECTOR_CLONES void UnitRays(int n, int on, const unsigned char* __restrict on_mirror, int unit, float tnear,
                                 int ring_test, const UnitRayFrame<T>* __restrict f, const T* __restrict vx,
                                 const T* __restrict vy, const T* __restrict vz, const T* __restrict Mx,
                                 const T* __restrict My, const T* __restrict Mz, T* __restrict dx, T* __restrict dy,
                                 T* __restrict dz, T* __restrict ox, T* __restrict oy, T* __restrict oz,
                                 float* __restrict tnear_out, int* __restrict from_mirror, int* __restrict from_camera,
                                 T* __restrict mount_t) {
  if (on == n) {
    UnitRaysOf<T, 1>(n, on_mirror, unit, tnear, ring_test, f, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ox, oy, oz,
                     tnear_out, from_mirror, from_camera, mount_t);
  } else if (on == 0) {
    UnitRaysOf<T, 2>(n, on_mirror, unit, tnear, ring_test, f, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ox, oy, oz,
                     tnear_out, from_mirror, from_camera, mount_t);
  } else {
    UnitRaysOf<T, 0>(n, on_mirror, unit, tnear, ring_test, f, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ox, oy, oz,
                     tnear_out, from_mirror, from_camera, mount_t);
  }
}

// The colours of a run of neighbouring pixels (len floats: 3 per pixel) from a chunk's samples (samples rows of
// `row` floats, the run's first colour at rgb), each weighted and summed in sample order (w r0 + w r1 + ...),
// into out, or added to it (add: a pixel split over chunks adds to what its earlier chunks left).
HOVS_VECTOR_CLONES
void SumSamples(int len, int samples, int row, float weight, const float* __restrict rgb, bool add,
                float* __restrict out) {
  // The last sample is added as the result is stored (a plain copy loop would become a library memcpy call).
  float sum[3 * RayBatch::kMax];
  const float* __restrict last = rgb + static_cast<ptrdiff_t>(samples - 1) * row;
  if (samples == 1) {
    if (add) {
      for (int j = 0; j < len; ++j) out[j] += weight * last[j];
    } else {
      for (int j = 0; j < len; ++j) out[j] = weight * last[j];
    }
    return;
  }
  for (int j = 0; j < len; ++j) sum[j] = weight * rgb[j];
  for (int smp = 1; smp < samples - 1; ++smp) {
    const float* __restrict r = rgb + static_cast<ptrdiff_t>(smp) * row;
    for (int j = 0; j < len; ++j) sum[j] += weight * r[j];
  }
  if (add) {
    for (int j = 0; j < len; ++j) out[j] += sum[j] + weight * last[j];
  } else {
    for (int j = 0; j < len; ++j) out[j] = sum[j] + weight * last[j];
  }
}

// R (column-major 3 x 3) times (x, y, 1) / |(x, y, 1)| for n points: unit rays.
HOVS_VECTOR_CLONES
void RotateRays(int n, const double* __restrict R, const double* __restrict x, const double* __restrict y,
                double* __restrict vx, double* __restrict vy, double* __restrict vz) {
  for (int i = 0; i < n; ++i) {
    const double s = 1.0 / std::sqrt(x[i] * x[i] + y[i] * y[i] + 1.0), sx = x[i] * s, sy = y[i] * s;
    vx[i] = R[0] * sx + R[3] * sy + R[6] * s;
    vy[i] = R[1] * sx + R[4] * sy + R[7] * s;
    vz[i] = R[2] * sx + R[5] * sy + R[8] * s;
  }
}

// The unit rays of n pixels of a camera without distortion in one pass: PinholeCamera::NormalisedFromImgBatch
// ((u - cx) / fx, (v - cy) / fy), then RotateRays (the same operations).
HOVS_VECTOR_CLONES
void PixelRays(int n, double fx, double fy, double cx, double cy, const double* __restrict R,
               const double* __restrict u, const double* __restrict v, double* __restrict vx, double* __restrict vy,
               double* __restrict vz) {
  for (int i = 0; i < n; ++i) {
    const double x = (u[i] - cx) / fx, y = (v[i] - cy) / fy;
    const double s = 1.0 / std::sqrt(x * x + y * y + 1.0), sx = x * s, sy = y * s;
    vx[i] = R[0] * sx + R[3] * sy + R[6] * s;
    vy[i] = R[1] * sx + R[4] * sy + R[7] * s;
    vz[i] = R[2] * sx + R[5] * sy + R[8] * s;
  }
}

// PixelRays in single precision for the colour samples: the pixel offsets from the principal point in double,
// then float throughout, with 1 / fx and 1 / fy as factors (x and y within a few 1e-7 relative of PixelRays').
HOVS_VECTOR_CLONES
void PixelRaysF(int n, double cx, double cy, float ifx, float ify, const float* __restrict R,
                const double* __restrict u, const double* __restrict v, float* __restrict vx, float* __restrict vy,
                float* __restrict vz) {
  for (int i = 0; i < n; ++i) {
    const float x = static_cast<float>(u[i] - cx) * ifx, y = static_cast<float>(v[i] - cy) * ify;
    const float s = 1.0f / std::sqrt(x * x + y * y + 1.0f), sx = x * s, sy = y * s;
    vx[i] = R[0] * sx + R[3] * sy + R[6] * s;
    vy[i] = R[1] * sx + R[4] * sy + R[7] * s;
    vz[i] = R[2] * sx + R[5] * sy + R[8] * s;
  }
}

// Where each ray of a batch starts: via[i] = 1 on unit's mirror (on_mirror[i]), else 0 (unit's camera, or a
// pinhole camera when unit < 0); the matching from_mirror / from_camera (-1: none) and tnear.
template <class T>
HOVS_VECTOR_CLONES void RayOrigins(int n, const unsigned char* __restrict on_mirror, int unit, float tnear,
                                   T* __restrict via, float* __restrict tnear_out, int* __restrict from_mirror,
                                   int* __restrict from_camera) {
  for (int i = 0; i < n; ++i) {
    const bool m = on_mirror[i] != 0;
    via[i] = m ? T(1) : T(0);
    tnear_out[i] = tnear;
    from_mirror[i] = m ? unit : -1;
    from_camera[i] = m ? -1 : unit;
  }
}

// The ground-truth channels (GroundTruth's order) of m pixel-centre rays, channel c of ray k at
// out[c * RayBatch::kMax + k], from the ray set-up (valid, from_mirror, mirror point M), the hits and the
// viewpoint c: range, point and normal where the ray hit something (else infinity and zeros), object id (0: sky),
// mirror mask (the ray left a mirror and did not meet the camera's own body) and the mirror point (where it left
// a mirror). The range is (p - c).norm() as Eigen sums it, ((x^2 + y^2) + z^2), then the square root. Vectorised.
HOVS_VECTOR_CLONES
void GroundTruthLanes(int m, const unsigned char* __restrict valid, const int* __restrict from_mirror,
                      const unsigned char* __restrict hit, const int* __restrict object_id,
                      const double* __restrict c, const double* __restrict px, const double* __restrict py,
                      const double* __restrict pz, const double* __restrict nx, const double* __restrict ny,
                      const double* __restrict nz, const double* __restrict Mx, const double* __restrict My,
                      const double* __restrict Mz, float* __restrict out) {
  constexpr int K = RayBatch::kMax;
  const float inf = std::numeric_limits<float>::infinity();
  const double c0 = c[0], c1 = c[1], c2 = c[2];
  for (int k = 0; k < m; ++k) {
    const double x = px[k] - c0, y = py[k] - c1, z = pz[k] - c2, range = std::sqrt(x * x + y * y + z * z);
    const int live = valid[k] != 0 ? 1 : 0;
    const int met = live & (hit[k] != 0 ? 1 : 0);
    const int via = live & (from_mirror[k] >= 0 ? 1 : 0);
    const int seen = via & (object_id[k] != kCameraBodyId ? 1 : 0);
    out[k] = met ? static_cast<float>(range) : inf;
    out[K + k] = met ? static_cast<float>(px[k]) : 0.0f;
    out[2 * K + k] = met ? static_cast<float>(py[k]) : 0.0f;
    out[3 * K + k] = met ? static_cast<float>(pz[k]) : 0.0f;
    out[4 * K + k] = met ? static_cast<float>(nx[k]) : 0.0f;
    out[5 * K + k] = met ? static_cast<float>(ny[k]) : 0.0f;
    out[6 * K + k] = met ? static_cast<float>(nz[k]) : 0.0f;
    out[7 * K + k] = met ? static_cast<float>(object_id[k]) : 0.0f;
    out[8 * K + k] = seen ? 1.0f : 0.0f;
    out[9 * K + k] = via ? static_cast<float>(Mx[k]) : 0.0f;
    out[10 * K + k] = via ? static_cast<float>(My[k]) : 0.0f;
    out[11 * K + k] = via ? static_cast<float>(Mz[k]) : 0.0f;
  }
}

// Pixel k's 12 ground-truth channels (c at t[c * RayBatch::kMax]) into the frame at v (16-byte aligned: frames
// are, and a pixel is 48 bytes). Streamed past the caches where the CPU can (the frame's 290 MB of ground truth
// is not read again while rendering; a row of a tile fills whole cache lines), plain stores elsewhere.
inline void StoreGroundTruthPixel(const float* t, float* v) {
  constexpr int K = RayBatch::kMax;
#if defined(__SSE__)
  _mm_stream_ps(v, _mm_setr_ps(t[0], t[K], t[2 * K], t[3 * K]));
  _mm_stream_ps(v + 4, _mm_setr_ps(t[4 * K], t[5 * K], t[6 * K], t[7 * K]));
  _mm_stream_ps(v + 8, _mm_setr_ps(t[8 * K], t[9 * K], t[10 * K], t[11 * K]));
#else
  for (int c = 0; c < GroundTruth::kChannels; ++c) v[c] = t[c * K];
#endif
}

// Thin-lens camera rays of n image points of an undistorted camera (or of undistorted normalised points, given
// with unit focal lengths and a zero principal point), mapped to a target frame. With thin = 1, the ray
// from the aperture point o = lens_radius (disc_x, disc_y, 0) towards the pinhole ray's point on the plane
// z = focus_distance, f (x, y, 1) with (x, y) = ((u - cx) / fx, (v - cy) / fy); with thin = 0, from the centre
// along (x, y, 1). Directions normalised (one square root and one division per ray); origin and direction mapped by
// target_from_cam (R column-major, t: mirror_from_cam for a unit, world_from_cam for a pinhole view). ifx, ify:
// 1 / fx, 1 / fy.
HOVS_VECTOR_CLONES
void ThinLensRays(int n, double ifx, double ify, double cx, double cy, double lens_radius, double focus_distance,
                  int thin, const double* __restrict R, const double* __restrict t, const double* __restrict u,
                  const double* __restrict v, const double* __restrict disc_x, const double* __restrict disc_y,
                  double* __restrict omx, double* __restrict omy, double* __restrict omz,
                  double* __restrict vmx, double* __restrict vmy, double* __restrict vmz) {
  const double f = thin ? focus_distance : 1.0, r = thin ? lens_radius : 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = (u[i] - cx) * ifx, y = (v[i] - cy) * ify;
    const double ox = r * disc_x[i], oy = r * disc_y[i];
    const double ex = x * f - ox, ey = y * f - oy, ez = f;
    const double inv = 1.0 / std::sqrt(ex * ex + ey * ey + ez * ez);
    const double dx = ex * inv, dy = ey * inv, dz = ez * inv;
    omx[i] = R[0] * ox + R[3] * oy + t[0];
    omy[i] = R[1] * ox + R[4] * oy + t[1];
    omz[i] = R[2] * ox + R[5] * oy + t[2];
    vmx[i] = R[0] * dx + R[3] * dy + R[6] * dz;
    vmy[i] = R[1] * dx + R[4] * dy + R[7] * dz;
    vmz[i] = R[2] * dx + R[5] * dy + R[8] * dz;
  }
}

// A unit's motion during the exposure (CatadioptricUnit::WorldFromMirrorAt): at time tau its world_from_mirror is
// the rotation by angle rate * tau about the unit axis (ax, ay, az) after world_from_mirror at 0, and its
// translation moves by velocity * tau.
struct UnitMotion {
  double rate = 0, axis[3] = {0, 0, 1}, velocity[3] = {0, 0, 0};
};

// How thin-lens samples past the rim are traced. own = 1: as the unit's own straight camera rays (from_camera =
// unit: RayScene masks off the unit's mirror and lens face, which they cannot meet, and ends them on the mount
// ring at mount_t, here computed in the mirror frame: the annulus r0 <= r <= r1 of the plane z = zr, where
// ring = 1); own = 0: as any ray (from_camera = -1, mount_t = -1: Embree finds what they meet).
struct LensRayRing {
  int own = 0, ring = 0;
  double zr = 0, r02 = 0, r12 = 0;
};

// The world rays of thin-lens samples (ThinLensRays, then the mirror): where on_mirror[i], from the mirror point M
// along the reflected direction, else from the aperture point along the camera ray (both in the mirror frame),
// mapped by world_from_mirror (R column-major, t) at the sample's time tau[i]: kMoving, the rotation by rate *
// tau about the axis (Rodrigues' formula; its sine and cosine from core/sincos.h) after R, and t + velocity *
// tau; else at time 0.
template <bool kMoving>
__attribute__((always_inline)) inline void ThinLensWorldRaysOf(
    int n, const unsigned char* __restrict on_mirror, int unit, const double* __restrict R, const double* __restrict t,
    const UnitMotion& motion, const LensRayRing& ring, const double* __restrict tau, const double* __restrict Mx,
    const double* __restrict My, const double* __restrict Mz, const double* __restrict mdx,
    const double* __restrict mdy, const double* __restrict mdz, const double* __restrict omx, const double* __restrict omy,
    const double* __restrict omz, const double* __restrict vmx, const double* __restrict vmy,
    const double* __restrict vmz, double* __restrict ox, double* __restrict oy, double* __restrict oz,
    double* __restrict dx, double* __restrict dy, double* __restrict dz, int* __restrict from_mirror,
    int* __restrict from_camera, double* __restrict mount_t) {
  const double zr = ring.zr, r02 = ring.r02, r12 = ring.r12;
  const int own_unit = ring.own ? unit : -1, ring_test = ring.own & ring.ring;
  const double a0 = motion.axis[0], a1 = motion.axis[1], a2 = motion.axis[2], turns = motion.rate / (2 * M_PI);
  const double w0 = motion.velocity[0], w1 = motion.velocity[1], w2 = motion.velocity[2];
  for (int i = 0; i < n; ++i) {
    const bool m = on_mirror[i] != 0;
    const double X0 = m ? Mx[i] : omx[i], X1 = m ? My[i] : omy[i], X2 = m ? Mz[i] : omz[i];
    const double D0 = m ? mdx[i] : vmx[i], D1 = m ? mdy[i] : vmy[i], D2 = m ? mdz[i] : vmz[i];
    double p0 = R[0] * X0 + R[3] * X1 + R[6] * X2, p1 = R[1] * X0 + R[4] * X1 + R[7] * X2,
           p2 = R[2] * X0 + R[5] * X1 + R[8] * X2;
    double q0 = R[0] * D0 + R[3] * D1 + R[6] * D2, q1 = R[1] * D0 + R[4] * D1 + R[7] * D2,
           q2 = R[2] * D0 + R[5] * D1 + R[8] * D2;
    double e0 = t[0], e1 = t[1], e2 = t[2];
    if (kMoving) {
      double sn, cs;
      SinCosOfTurns(turns * tau[i], &sn, &cs);
      const double k = 1 - cs;
      const double ap = a0 * p0 + a1 * p1 + a2 * p2, aq = a0 * q0 + a1 * q1 + a2 * q2;
      const double r0 = cs * p0 + sn * (a1 * p2 - a2 * p1) + k * ap * a0;
      const double r1 = cs * p1 + sn * (a2 * p0 - a0 * p2) + k * ap * a1;
      const double r2 = cs * p2 + sn * (a0 * p1 - a1 * p0) + k * ap * a2;
      const double s0 = cs * q0 + sn * (a1 * q2 - a2 * q1) + k * aq * a0;
      const double s1 = cs * q1 + sn * (a2 * q0 - a0 * q2) + k * aq * a1;
      const double s2 = cs * q2 + sn * (a0 * q1 - a1 * q0) + k * aq * a2;
      p0 = r0, p1 = r1, p2 = r2, q0 = s0, q1 = s1, q2 = s2;
      e0 += w0 * tau[i], e1 += w1 * tau[i], e2 += w2 * tau[i];
    }
    ox[i] = p0 + e0, oy[i] = p1 + e1, oz[i] = p2 + e2;
    dx[i] = q0, dy[i] = q1, dz[i] = q2;
    from_mirror[i] = m ? unit : -1;
    // A straight ray's distance to the mount ring (the mirror-frame ray: vm is unit, so t is the distance along
    // the world ray, at any time); 0 where it misses the ring, -1 where not computed.
    const double w = vmz[i] != 0 ? vmz[i] : 1.0;
    const double tr = (zr - omz[i]) / w, px = omx[i] + tr * vmx[i], py = omy[i] + tr * vmy[i];
    const double r2 = px * px + py * py;
    const bool hits_ring = vmz[i] != 0 && tr > 1e-5 && r2 >= r02 && r2 <= r12;
    from_camera[i] = m ? -1 : own_unit;
    mount_t[i] = m ? -1.0 : (ring_test ? (hits_ring ? tr : 0.0) : -1.0);
  }
}

HOVS_VECTOR_CLONES
void ThinLensWorldRays(int n, const unsigned char* __restrict on_mirror, int unit, const double* __restrict R,
                       const double* __restrict t, const UnitMotion& motion, const LensRayRing& ring,
                       const double* __restrict tau, const double* __restrict Mx, const double* __restrict My,
                       const double* __restrict Mz,
                       const double* __restrict mdx, const double* __restrict mdy, const double* __restrict mdz,
                       const double* __restrict omx, const double* __restrict omy, const double* __restrict omz,
                       const double* __restrict vmx, const double* __restrict vmy, const double* __restrict vmz,
                       double* __restrict ox, double* __restrict oy, double* __restrict oz, double* __restrict dx,
                       double* __restrict dy, double* __restrict dz, int* __restrict from_mirror,
                       int* __restrict from_camera, double* __restrict mount_t) {
  if (tau) {
    ThinLensWorldRaysOf<true>(n, on_mirror, unit, R, t, motion, ring, tau, Mx, My, Mz, mdx, mdy, mdz, omx, omy, omz,
                              vmx, vmy, vmz, ox, oy, oz, dx, dy, dz, from_mirror, from_camera, mount_t);
  } else {
    ThinLensWorldRaysOf<false>(n, on_mirror, unit, R, t, motion, ring, tau, Mx, My, Mz, mdx, mdy, mdz, omx, omy,
                               omz, vmx, vmy, vmz, ox, oy, oz, dx, dy, dz, from_mirror, from_camera, mount_t);
  }
}

class RayMaker {
 public:
  RayMaker(const RayScene& scene, const ViewCamera& cam, const RenderOptions& o)
      : scene_(scene), cam_(cam), lens_radius_(o.lens_radius), focus_distance_(o.focus_distance) {
    if (cam.unit >= 0) {
      HOVS_REQUIRE(cam.unit < static_cast<int>(scene.description().units.size()), "render",
                   "the scene has no unit ", cam.unit);
      unit_ = &scene.description().units[cam.unit];
      reflector_.emplace(unit_->rig.mirror);
      mirror_from_cam_ = unit_->rig.cam_from_mirror.Inverse();
      world_from_cam_ = unit_->world_from_mirror * mirror_from_cam_;
      // Rotation matrices for the per-sample transforms (a quaternion rotation costs twice as much).
      R_mirror_from_cam_ = mirror_from_cam_.rotation.toRotationMatrix(), t_mirror_from_cam_ = mirror_from_cam_.translation;
      R_world_from_mirror_ = unit_->world_from_mirror.rotation.toRotationMatrix();
      t_world_from_mirror_ = unit_->world_from_mirror.translation;
      viewpoint_ = unit_->world_from_mirror.translation;
      width_ = unit_->rig.camera.width, height_ = unit_->rig.camera.height;
      // The single-precision colour path: a unit's camera without distortion, at time 0, through a pinhole.
      single_ = unit_->rig.camera.distortion.IsZero() && !(o.lens_radius > 0) && !(o.exposure_time > 0);
      R_mirror_from_cam_f_ = R_mirror_from_cam_.cast<float>();
      SetFrame(&frame_d_), SetFrame(&frame_f_);
      motion_.rate = unit_->angular_velocity.norm();
      if (motion_.rate > 0)
        for (int k = 0; k < 3; ++k) motion_.axis[k] = unit_->angular_velocity(k) / motion_.rate;
      for (int k = 0; k < 3; ++k) motion_.velocity[k] = unit_->velocity(k);
      // Thin-lens samples past the rim are the unit's own straight camera rays when the whole aperture lies inside
      // the mirror's lower nappe, as the camera centre does: from there a ray that misses the mirror within the rim
      // never meets it (MirrorReflector::MissesRim's argument), and it leaves the lens face forwards.
      lens_ring_.own = ApertureInLowerNappe() ? 1 : 0;
      lens_ring_.ring = unit_->mount_outer_radius > 0 ? 1 : 0;
      lens_ring_.zr = unit_->rig.mirror.RimZ();
      lens_ring_.r02 = unit_->rig.mirror.RimRadius() * unit_->rig.mirror.RimRadius();
      lens_ring_.r12 = unit_->mount_outer_radius * unit_->mount_outer_radius;
      // Under motion blur the path from the camera to the mount ring must stay clear over the whole exposure.
      mount_paths_clear_ = !(o.exposure_time > 0) || scene.MountPathClearDuring(cam.unit, o.exposure_time);
    } else {
      cam.pinhole.Check("render camera");
      world_from_cam_ = cam.world_from_cam;
      viewpoint_ = cam.world_from_cam.translation;
      width_ = cam.pinhole.width, height_ = cam.pinhole.height;
    }
    R_world_from_cam_ = world_from_cam_.rotation.toRotationMatrix();
    HOVS_REQUIRE(width_ > 0 && height_ > 0, "render", "the camera has no image size");
  }
  int width() const { return width_; }
  int height() const { return height_; }
  const Vec3d& viewpoint() const { return viewpoint_; }
  // The camera whose pixels the rays leave.
  const PinholeCamera<double>& camera() const { return unit_ ? unit_->rig.camera : cam_.pinhole; }
  // True when the colour samples take MakeBatchF (single precision).
  bool single() const { return single_; }

  // MakeBatch's vectorised path in single precision, for the colour samples when single(): the same steps in
  // float (PixelRaysF, the float MirrorReflector::ReflectBatch, UnitRays on floats). Rays
  // within about 1e-7 relative of MakeBatch's (tests bound them), the precision Embree traces them in.
  void MakeBatchF(int n, const double* u, const double* v, RayBatchF* b) const {
    b->n = n;
    b->timed = false, b->mirror_frame = false, b->mount_paths_clear = true;
    const PinholeCamera<double>& cam = unit_->rig.camera;
    alignas(64) float vx[RayBatch::kMax], vy[RayBatch::kMax], vz[RayBatch::kMax];
    alignas(64) float Mx[RayBatch::kMax], My[RayBatch::kMax], Mz[RayBatch::kMax];
    unsigned char on_mirror[RayBatch::kMax];
    PixelRaysF(n, cam.cx, cam.cy, static_cast<float>(1.0 / cam.fx), static_cast<float>(1.0 / cam.fy),
               R_mirror_from_cam_f_.data(), u, v, vx, vy, vz);
    std::fill(b->valid, b->valid + n, 1);
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    const int on = reflector_->ReflectBatch(t_mirror_from_cam_, n, vx, vy, vz, Mx, My, Mz, b->dx, b->dy, b->dz, on_mirror);
    // (A batch whose rays all meet the mirror, most of them, has no straight ray: no ring test.)
    UnitRays<float>(n, on, on_mirror, cam_.unit, 1e-5f, unit_->mount_outer_radius > 0 && on < n, &frame_f_, vx, vy, vz,
                    Mx, My, Mz, b->dx, b->dy, b->dz, b->ox, b->oy, b->oz, b->tnear, b->from_mirror, b->from_camera,
                    b->mount_t);
#pragma GCC diagnostic pop
  }

  // The rays of n image points (n <= RayBatch::kMax) into a batch, with each ray's mirror point (mirror frame;
  // meaningful where from_mirror >= 0). lens_x, lens_y: thin-lens aperture points on the unit disc, tau: times in
  // the exposure (MakeLensBatch, MakePinholeLensBatch); both null: a pinhole at time 0, whose camera rays are
  // reflected together (MirrorReflector::ReflectBatch).
  //
  // nx, ny (with u, v still given): the points' normalised coordinates ((u - cx) / fx, (v - cy) / fy), already
  // computed (pixel centres: one division per column and per row of a tile), for a camera without distortion.
  void MakeBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                 const double* tau, RayBatch* b, double* Mx, double* My, double* Mz, const double* nx = nullptr,
                 const double* ny = nullptr) const {
    b->n = n;
    b->timed = false, b->mirror_frame = false, b->mount_paths_clear = true;
    if ((lens_x || tau) && unit_) {
      MakeLensBatch(n, u, v, lens_x, lens_y, tau, b, Mx, My, Mz);
      return;
    }
    if (lens_x || tau) {   // a pinhole view through a thin lens (pinhole views do not move)
      MakePinholeLensBatch(n, u, v, lens_x, lens_y, b);
      std::fill(Mx, Mx + n, 0.0), std::fill(My, My + n, 0.0), std::fill(Mz, Mz + n, 0.0);   // no mirror
      return;
    }
    const PinholeCamera<double>& cam = unit_ ? unit_->rig.camera : cam_.pinhole;
    // The unit camera rays, in the mirror frame for a unit (reflected together), in the world for a pinhole.
    double vx[RayBatch::kMax], vy[RayBatch::kMax], vz[RayBatch::kMax];
    const double* R = unit_ ? R_mirror_from_cam_.data() : R_world_from_cam_.data();
    if (nx && ny && cam.distortion.IsZero()) {
      RotateRays(n, R, nx, ny, vx, vy, vz);
      std::fill(b->valid, b->valid + n, 1);
    } else if (cam.distortion.IsZero()) {
      PixelRays(n, cam.fx, cam.fy, cam.cx, cam.cy, R, u, v, vx, vy, vz);
      std::fill(b->valid, b->valid + n, 1);
    } else {
      double mx[RayBatch::kMax], my[RayBatch::kMax];
      cam.NormalisedFromImgBatch(n, u, v, mx, my, b->valid);
      RotateRays(n, R, mx, my, vx, vy, vz);
    }
    unsigned char on_mirror[RayBatch::kMax];
    // (GCC 12 reports the arrays as maybe uninitialised when n could be 0; the callees read only [0, n).)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    if (unit_) {
      const int on =
          reflector_->ReflectBatch(t_mirror_from_cam_, n, vx, vy, vz, Mx, My, Mz, b->dx, b->dy, b->dz, on_mirror);
      // Camera rays past the rim: where they meet the unit's mount ring, in the mirror frame where the rim test
      // was made (the world ray is the same ray rotated and moved, so the distance along it is the same).
      // RayScene traces them only up to it. tnear 1e-5: off the mirror, or off the lens face.
      // (A batch whose rays all meet the mirror, most of them, has no straight ray: no ring test.) Both kinds of
      // ray from the mirror frame to the world in one rotation.
      UnitRays<double>(n, on, on_mirror, cam_.unit, 1e-5f, unit_->mount_outer_radius > 0 && on < n, &frame_d_, vx, vy,
                       vz, Mx, My, Mz, b->dx, b->dy, b->dz, b->ox, b->oy, b->oz, b->tnear, b->from_mirror,
                       b->from_camera, b->mount_t);
    } else {
      std::fill(on_mirror, on_mirror + n, 0);
      double via[RayBatch::kMax];  // on_mirror as 0 / 1 (the pinhole camera has no mirror: all 0)
      RayOrigins(n, on_mirror, -1, 0.0f, via, b->tnear, b->from_mirror, b->from_camera);
      std::fill(b->mount_t, b->mount_t + n, -1.0);
      std::copy(vx, vx + n, b->dx), std::copy(vy, vy + n, b->dy), std::copy(vz, vz + n, b->dz);
      std::fill(b->ox, b->ox + n, world_from_cam_.translation.x());
      std::fill(b->oy, b->oy + n, world_from_cam_.translation.y());
      std::fill(b->oz, b->oz + n, world_from_cam_.translation.z());
    }
#pragma GCC diagnostic pop
  }

  // MakeBatch's thin-lens and motion-blur path for a unit's camera, vectorised (but for the undistortion): the
  // camera rays from the aperture (CameraLensRays), the mirror with an origin per ray (MirrorReflector::ReflectRays,
  // to the bit as Reflect), then the world rays at each sample's time (ThinLensWorldRays). Tests bound them against
  // the core's CamFromImg, ReflectCameraRay and WorldFromMirrorAt. The straight rays past the rim end on the unit's
  // mount ring, met in the unit's frame, as the pinhole samples' (LensRayRing).
  void MakeLensBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                     const double* tau, RayBatch* b, double* Mx, double* My, double* Mz) const {
    alignas(64) double omx[RayBatch::kMax], omy[RayBatch::kMax], omz[RayBatch::kMax], vmx[RayBatch::kMax],
        vmy[RayBatch::kMax], vmz[RayBatch::kMax];
    alignas(64) double mdx[RayBatch::kMax], mdy[RayBatch::kMax], mdz[RayBatch::kMax];
    unsigned char on_mirror[RayBatch::kMax];
    CameraLensRays(unit_->rig.camera, R_mirror_from_cam_.data(), t_mirror_from_cam_.data(), n, u, v, lens_x, lens_y,
                   b->valid, omx, omy, omz, vmx, vmy, vmz);
    reflector_->ReflectRays(n, omx, omy, omz, vmx, vmy, vmz, Mx, My, Mz, mdx, mdy, mdz, on_mirror);
    ThinLensWorldRays(n, on_mirror, cam_.unit, R_world_from_mirror_.data(), t_world_from_mirror_.data(), motion_,
                      lens_ring_, tau, Mx, My, Mz, mdx, mdy, mdz, omx, omy, omz, vmx, vmy, vmz, b->ox, b->oy, b->oz,
                      b->dx, b->dy, b->dz, b->from_mirror, b->from_camera, b->mount_t);
    // tnear 1e-5: off the mirror's sheet (float rounding of the origin), or off the camera's lens face.
    std::fill(b->tnear, b->tnear + n, 1e-5f);
    // Each ray's time, at which RayScene meets the moving units' parts.
    b->timed = tau != nullptr;
    b->mount_paths_clear = tau == nullptr || mount_paths_clear_;
    if (tau)
      for (int i = 0; i < n; ++i) b->time[i] = static_cast<float>(tau[i]);
    // The mirror rays in the mirror frame, where RayScene meets the moving unit's own parts.
    b->mirror_frame = scene_.OwnPartsInMirrorFrame(cam_.unit);
    if (b->mirror_frame) {
      std::copy(Mx, Mx + n, b->mox), std::copy(My, My + n, b->moy), std::copy(Mz, Mz + n, b->moz);
      std::copy(mdx, mdx + n, b->mdx), std::copy(mdy, mdy + n, b->mdy), std::copy(mdz, mdz + n, b->mdz);
    }
  }

  // A pinhole view's thin-lens samples (RenderInto gives pinhole views no motion blur): CameraLensRays mapped
  // straight to the world by world_from_cam (tests bound them against the core's CamFromImg).
  void MakePinholeLensBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                            RayBatch* b) const {
    CameraLensRays(cam_.pinhole, R_world_from_cam_.data(), world_from_cam_.translation.data(), n, u, v, lens_x, lens_y,
                   b->valid, b->ox, b->oy, b->oz, b->dx, b->dy, b->dz);
    std::fill(b->tnear, b->tnear + n, 0.0f);
    std::fill(b->from_mirror, b->from_mirror + n, -1);
    std::fill(b->from_camera, b->from_camera + n, -1);
    std::fill(b->mount_t, b->mount_t + n, -1.0);
  }

 private:
  // The thin-lens camera rays of n image points of cam (ThinLensRays; lens_x null or no lens radius: from the
  // centre), mapped by target_from_cam (R column-major, t); valid[i] = 0 where a point of a camera with lens
  // distortion cannot be undistorted (ThinLensRays then takes the undistorted normalised points as they are: unit
  // focal lengths, zero principal point).
  void CameraLensRays(const PinholeCamera<double>& cam, const double* R, const double* t, int n, const double* u,
                      const double* v, const double* lens_x, const double* lens_y, unsigned char* valid, double* ox,
                      double* oy, double* oz, double* dx, double* dy, double* dz) const {
    const bool thin = lens_x && lens_radius_ > 0, distorted = !cam.distortion.IsZero();
    alignas(64) double zeros[RayBatch::kMax], xn[RayBatch::kMax], yn[RayBatch::kMax];
    if (!thin) std::fill(zeros, zeros + n, 0.0);
    if (distorted) {
      cam.NormalisedFromImgBatch(n, u, v, xn, yn, valid);
    } else {
      std::fill(valid, valid + n, 1);
    }
    ThinLensRays(n, distorted ? 1.0 : 1.0 / cam.fx, distorted ? 1.0 : 1.0 / cam.fy, distorted ? 0.0 : cam.cx,
                 distorted ? 0.0 : cam.cy, lens_radius_, focus_distance_, thin ? 1 : 0, R, t, distorted ? xn : u,
                 distorted ? yn : v, thin ? lens_x : zeros, thin ? lens_y : zeros, ox, oy, oz, dx, dy, dz);
  }

  const RayScene& scene_;
  const ViewCamera& cam_;
  double lens_radius_ = 0, focus_distance_ = 1;
  const CatadioptricUnit* unit_ = nullptr;
  std::optional<MirrorReflector> reflector_;   // the unit's mirror (same law as rig.ReflectCameraRay)
  Rigid3d world_from_cam_, mirror_from_cam_;
  Eigen::Matrix3d R_mirror_from_cam_ = Eigen::Matrix3d::Identity(), R_world_from_mirror_ = Eigen::Matrix3d::Identity();
  Vec3d t_mirror_from_cam_ = Vec3d::Zero(), t_world_from_mirror_ = Vec3d::Zero();
  Vec3d viewpoint_ = Vec3d::Zero();
  Eigen::Matrix3d R_world_from_cam_ = Eigen::Matrix3d::Identity();
  bool single_ = false;
  Eigen::Matrix3f R_mirror_from_cam_f_ = Eigen::Matrix3f::Identity();
  UnitMotion motion_;              // the unit's motion during the exposure
  LensRayRing lens_ring_;          // how thin-lens samples past the rim are traced
  bool mount_paths_clear_ = true;  // RayScene::MountPathClearDuring the exposure (blurred batches)
  UnitRayFrame<double> frame_d_;   // UnitRays' view of the unit, in double and in float
  UnitRayFrame<float> frame_f_;

  // True when the thin-lens aperture (the disc of radius lens_radius_ about the camera centre in the lens plane)
  // lies inside the unit's lower nappe, below the rim plane, with a margin: checked on a polygon circumscribing
  // its boundary circle (the region is convex).
  bool ApertureInLowerNappe() const {
    const HyperboloidMirror<double>& mirror = unit_->rig.mirror;
    const double c = mirror.c(), ia2 = 1 / (mirror.a * mirror.a), ib2 = 1 / (mirror.b * mirror.b);
    const int k = 64;
    const double r = lens_radius_ / std::cos(M_PI / k);
    for (int i = 0; i < k; ++i) {
      const Vec3d p = mirror_from_cam_ * Vec3d(r * std::cos(2 * M_PI * i / k), r * std::sin(2 * M_PI * i / k), 0);
      const double oz = p.z() + c;
      if (!(oz < 0 && oz * oz * ia2 - (p.x() * p.x() + p.y() * p.y()) * ib2 >= 1 + 1e-9 && p.z() < mirror.RimZ()))
        return false;
    }
    return true;
  }

  // The unit's ring, camera centre and world_from_mirror, rounded to T.
  template <class T>
  void SetFrame(UnitRayFrame<T>* f) const {
    f->zr = static_cast<T>(unit_->rig.mirror.RimZ());
    f->r0 = static_cast<T>(unit_->rig.mirror.RimRadius());
    f->r1 = static_cast<T>(unit_->mount_outer_radius);
    for (int k = 0; k < 3; ++k) {
      f->c_m[k] = static_cast<T>(t_mirror_from_cam_(k));
      f->t[k] = static_cast<T>(t_world_from_mirror_(k));
      f->c_w[k] = static_cast<T>(world_from_cam_.translation(k));
    }
    for (int k = 0; k < 9; ++k) f->R[k] = static_cast<T>(R_world_from_mirror_.data()[k]);
  }
  int width_ = 0, height_ = 0;
};

}  // namespace

std::size_t FrameMemoryBytes(int width, int height, bool ground_truth) {
  const std::size_t npx = static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0));
  return npx * sizeof(float) * (3 + (ground_truth ? GroundTruth::kChannels : 0) + 3);
}

void CheckFrameMemory(const std::string& where, int width, int height, bool ground_truth, std::size_t held,
                      std::optional<std::size_t> available) {
  const std::size_t need = FrameMemoryBytes(width, height, ground_truth);
  if (need <= held) return;
  const std::string frame = "a " + std::to_string(width) + " x " + std::to_string(height) + " frame" +
                            (ground_truth ? " with ground truth" : "") + " (its buffers and the sensor image" +
                            (held > 0 ? ", less what its buffers hold" : "") + ")";
  RequireMemory(where, frame, need - held, available, "render fewer pixels or free memory");
}

void SampleRays(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options, int n, const double* u,
                const double* v, const double* disc_x, const double* disc_y, const double* tau, RayBatch* out) {
  HOVS_REQUIRE(n >= 0 && n <= RayBatch::kMax, "SampleRays", "at most ", RayBatch::kMax, " points (got ", n, ")");
  HOVS_REQUIRE((disc_x == nullptr) == (disc_y == nullptr), "SampleRays", "aperture points need both coordinates");
  options.Check("render");
  const RayMaker maker(scene, camera, options);
  double Mx[RayBatch::kMax], My[RayBatch::kMax], Mz[RayBatch::kMax];
  maker.MakeBatch(n, u, v, disc_x, disc_y, tau, out, Mx, My, Mz);
}

Frame Render(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options) {
  Frame f;
  RenderInto(scene, camera, options, &f);
  return f;
}

void RenderInto(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options, Frame* frame) {
  options.Check("render");
  const auto start = std::chrono::steady_clock::now();
  const RayMaker maker(scene, camera, options);
  const bool lens = options.lens_radius > 0, blur = options.exposure_time > 0 && camera.unit >= 0;
  if (blur) {   // the moving unit stays where Embree's single precision holds (RayScene checks its start)
    const CatadioptricUnit& u = scene.description().units[camera.unit];
    const Vec3d end = u.WorldFromMirrorAt(options.exposure_time).translation;
    HOVS_REQUIRE(end.allFinite() && end.cwiseAbs().maxCoeff() <= kWorldExtent, "render.exposure_time", "unit ", u.name,
                 " moves beyond ", kWorldExtent, " m of the world origin during the exposure");
    HOVS_REQUIRE(options.exposure_time <= scene.MotionHorizon(), "render.exposure_time", "the scene's units turn so "
                 "fast that motion blur covers at most ", scene.MotionHorizon(), " s (got ", options.exposure_time, ")");
  }
  Frame& f = *frame;
  CheckFrameMemory(camera.unit >= 0 ? "render (unit " + scene.description().units[camera.unit].name + "'s camera)"
                                    : std::string("render (pinhole camera)"),
                   maker.width(), maker.height(), options.ground_truth,
                   sizeof(float) * (f.rgb.capacity() + f.truth.data.capacity()), AvailableMemoryBytes());
  f.width = maker.width(), f.height = maker.height();
  if (!options.ground_truth) f.truth.data.clear();
  const size_t npx = static_cast<size_t>(f.width) * f.height;
  // Zeroed in parallel (the first touch of ~360 MB at full resolution with ground truth).
  f.rgb.resize(npx * 3);
  if (options.ground_truth) f.truth.data.resize(npx * GroundTruth::kChannels);
  const auto zero = [](PixelBuffer* b) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, b->size(), size_t(1) << 20), [&](const tbb::blocked_range<size_t>& r) {
      std::fill(b->begin() + static_cast<std::ptrdiff_t>(r.begin()), b->begin() + static_cast<std::ptrdiff_t>(r.end()), 0.0f);
    });
  };
  // Tiles write every pixel and channel of the region (first touch in the rendering threads); only pixels
  // outside a region need zeros.
  const bool whole = options.region.Empty() ||
                     (options.region.x0 <= 0 && options.region.y0 <= 0 && options.region.x1 >= f.width &&
                      options.region.y1 >= f.height);
  if (!whole) {
    zero(&f.rgb);
    zero(&f.truth.data);
  }

  const int tile = 16;
  RenderOptions::Region roi = options.region;
  if (roi.Empty()) roi = {0, 0, f.width, f.height};
  roi.x0 = std::max(0, roi.x0), roi.y0 = std::max(0, roi.y0);
  roi.x1 = std::min(f.width, roi.x1), roi.y1 = std::min(f.height, roi.y1);
  HOVS_REQUIRE(!roi.Empty(), "render.region", "the region does not overlap the image");
  const int tiles_x = (roi.x1 - roi.x0 + tile - 1) / tile, tiles_y = (roi.y1 - roi.y0 + tile - 1) / tile;
  const int ntiles = tiles_x * tiles_y;
  const int n = options.samples;
  const int grid = static_cast<int>(std::lround(std::sqrt(n)));
  const bool stratified = grid * grid == n;
  const double inv_grid = 1.0 / grid;
  const float weight = 1.0f / n;
  const uint64_t seed_mix = options.seed * 0x100000001B3ull;
  // Sample s of a pixel lies in stratum (s % grid, s / grid); a chunk of samples holds per_chunk whole pixels,
  // or 0 when a pixel has more samples than a chunk (then each chunk holds part of one pixel).
  constexpr int kMaxBatch = RayBatch::kMax;
  const int per_chunk = kMaxBatch / n;
  std::atomic<uint64_t> rays{0}, embree_rays{0};
  std::atomic<int> done{0};
  const bool progress = options.progress && isatty(STDERR_FILENO);
  int last_percent = -1;

  tbb::parallel_for(tbb::blocked_range<int>(0, ntiles), [&](const tbb::blocked_range<int>& range) {
    // Per task: one batch of up to 256 rays in structure-of-arrays form, reused for every chunk.
    constexpr int kMax = RayBatch::kMax;
    const auto batch = std::make_unique<RayBatch>();
    const auto batch_f = maker.single() ? std::make_unique<RayBatchF>() : nullptr;
    struct Scratch {
      double u[kMax], v[kMax], Mx[kMax], My[kMax], Mz[kMax], tau[kMax];
      double nx[kMax], ny[kMax], col_x[kMax], row_y[kMax];   // pixel centres' normalised coordinates
      double disc_x[kMax], disc_y[kMax];   // thin-lens aperture points (unit disc)
      int px[kMax];
      // The chunk's pixels: index in the frame, centre.
      int pixel[kMax];
      int run_at[kMax], run_len[kMax];   // runs of neighbouring pixels (along a tile row) in the chunk
      int pixel_x[kMax], pixel_y[kMax];
      float rgb[3 * kMax];
      HitBatch hits;            // the ground-truth rays' hits
      alignas(64) float truth[GroundTruth::kChannels * kMax];   // their ground truth, channel by channel
    };
    const auto scratch = std::make_unique<Scratch>();
    Scratch& sc = *scratch;
    uint64_t task_rays = 0, task_embree = 0;
    for (int ti = range.begin(); ti != range.end(); ++ti) {
      const int x0 = roi.x0 + (ti % tiles_x) * tile, y0 = roi.y0 + (ti / tiles_x) * tile;
      const int x1 = std::min(x0 + tile, roi.x1), y1 = std::min(y0 + tile, roi.y1);
      const int tw = x1 - x0, tile_px = tw * (y1 - y0);
      // The samples of the tile in chunks of P whole pixels (or of part of one pixel, P = 1, when it has more
      // samples than a chunk holds), ordered by sample index, then pixel: sample s of the chunk's pixel q is
      // k = (s - s_begin) P + q. So a packet holds one stratum of 16 neighbouring pixels, and each pixel's sum
      // below runs over contiguous rows of colours.
      int x = x0, y = y0, s0 = 0;
      for (int p0 = 0; p0 < tile_px;) {
        const int pixels = std::min(per_chunk, tile_px - p0), count = std::min(n - s0, kMax);
        const int P = per_chunk > 0 ? pixels : 1, m = per_chunk > 0 ? pixels * n : count;
        const int s_begin = per_chunk > 0 ? 0 : s0, s_end = per_chunk > 0 ? n : s0 + count;
        int xq = x, yq = y;   // the chunk's pixels, in runs along the tile's rows (run r: run_at[r] .. + run_len[r])
        int runs = 0;
        for (int q = 0; q < P;) {
          const int len = std::min(x1 - xq, P - q), base = yq * f.width + xq;
          for (int i = 0; i < len; ++i) {
            sc.pixel[q + i] = base + i;
            sc.pixel_x[q + i] = xq + i, sc.pixel_y[q + i] = yq;
          }
          sc.run_at[runs] = q, sc.run_len[runs++] = len;
          q += len;
          if ((xq += len) == x1) xq = x0, ++yq;
        }
        JitteredSamples(P, s_begin, s_end, grid, seed_mix, stratified, inv_grid, sc.pixel, sc.pixel_x, sc.pixel_y,
                        sc.u, sc.v);
        if (lens || blur) {   // aperture points (uniform on the unit disc) and exposure times
          LensSamples(P, s_begin, s_end, seed_mix, lens, blur ? options.exposure_time : 0.0, sc.pixel, sc.disc_x,
                      sc.disc_y, sc.tau);
        }
        if (batch_f) {   // (every ray of this path is valid: MakeBatchF has no domain limit)
          maker.MakeBatchF(m, sc.u, sc.v, batch_f.get());
          task_embree += static_cast<uint64_t>(scene.Colours(*batch_f, sc.rgb));
          task_rays += static_cast<uint64_t>(m);
        } else {
          maker.MakeBatch(m, sc.u, sc.v, lens ? sc.disc_x : nullptr, lens ? sc.disc_y : nullptr,
                          blur ? sc.tau : nullptr, batch.get(), sc.Mx, sc.My, sc.Mz);
          task_embree += static_cast<uint64_t>(scene.Colours(*batch, sc.rgb));
          for (int k = 0; k < m; ++k) task_rays += batch->valid[k];
        }
        // Each pixel's samples summed in order, weighted (w r0 + w r1 + ...: the first sample starts the sum, so
        // the frame needs no zeroing; a pixel split over chunks adds to what its earlier chunks left): over the
        // chunk's colour rows at once, then written per run of neighbouring pixels.
        for (int r = 0; r < runs; ++r) {
          const int qa = sc.run_at[r];
          SumSamples(3 * sc.run_len[r], s_end - s_begin, 3 * P, weight, sc.rgb + 3 * qa, s_begin > 0,
                     &f.rgb[3 * static_cast<size_t>(sc.pixel[qa])]);
        }
        if (per_chunk > 0) {
          p0 += pixels;
          x = xq, y = yq;
        } else if ((s0 += count) == n) {  // the pixel's last chunk
          s0 = 0, ++p0;
          if (++x == x1) x = x0, ++y;
        }
      }
      if (options.ground_truth) {
        // The pixel-centre rays of the tile, without colour. Without distortion their normalised coordinates
        // are a column's and a row's (the same divisions as PixelRays, once per column and row).
        const PinholeCamera<double>& gc = maker.camera();
        const bool separable = gc.distortion.IsZero();
        if (separable) {
          for (int i = 0; i < tw; ++i) sc.col_x[i] = (static_cast<double>(x0 + i) - gc.cx) / gc.fx;
          for (int j = 0; j < y1 - y0; ++j) sc.row_y[j] = (static_cast<double>(y0 + j) - gc.cy) / gc.fy;
        }
        int gx = x0, gy = y0;
        for (int p0 = 0; p0 < tile_px; p0 += kMax) {
          const int m = std::min(kMax, tile_px - p0);
          int runs = 0;
          for (int k = 0; k < m;) {   // in runs along the tile's rows
            const int len = std::min(x1 - gx, m - k), base = gy * f.width + gx;
            sc.run_at[runs] = k, sc.run_len[runs++] = len;
            for (int i = 0; i < len; ++i) sc.px[k + i] = base + i;
            if (!separable) {
              for (int i = 0; i < len; ++i) sc.u[k + i] = gx + i, sc.v[k + i] = gy;
            } else {
              std::copy(sc.col_x + (gx - x0), sc.col_x + (gx - x0) + len, sc.nx + k);
              std::fill(sc.ny + k, sc.ny + k + len, sc.row_y[gy - y0]);
            }
            k += len;
            if ((gx += len) == x1) gx = x0, ++gy;
          }
          maker.MakeBatch(m, sc.u, sc.v, nullptr, nullptr, nullptr, batch.get(), sc.Mx, sc.My, sc.Mz,
                          separable ? sc.nx : nullptr, separable ? sc.ny : nullptr);
          task_embree += static_cast<uint64_t>(scene.Geometry(*batch, &sc.hits));
          const HitBatch& H = sc.hits;
          static_assert(GroundTruth::kChannels == 12, "the pixel below is 12 floats");
          GroundTruthLanes(m, batch->valid, batch->from_mirror, H.hit, H.object_id, maker.viewpoint().data(), H.px, H.py, H.pz, H.nx,
                           H.ny, H.nz, sc.Mx, sc.My, sc.Mz, sc.truth);
          for (int k = 0; k < m; ++k) task_rays += batch->valid[k];
          // Every channel of every pixel is written (the buffer is not zeroed first), in runs along the tile's rows.
          for (int r = 0; r < runs; ++r) {
            const int k = sc.run_at[r], e = k + sc.run_len[r];
            float* v = &f.truth.data[static_cast<size_t>(sc.px[k]) * GroundTruth::kChannels];
            for (int i = k; i < e; ++i, v += GroundTruth::kChannels) StoreGroundTruthPixel(sc.truth + i, v);
          }
        }
      }
      if (progress) {
        const int d = ++done;   // (only here: an atomic shared by all threads costs about 0.6 % of a frame)
        const int percent = static_cast<int>(100.0 * d / ntiles);
        if (percent != last_percent && percent % 5 == 0) {
          last_percent = percent;
          std::fprintf(stderr, "\rrender [%-20s] %3d%%", std::string(percent / 5, '#').c_str(), percent);
          if (d == ntiles) std::fprintf(stderr, "\n");
        }
      }
    }
#if defined(__SSE__)
    _mm_sfence();   // the streamed ground truth, ordered before the task ends
#endif
    rays += task_rays;
    embree_rays += task_embree;
  });
  f.rays = rays;
  f.embree_rays = embree_rays;
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

namespace {

// The standard normal quantile at p in (0, 1): Acklam's rational approximations (relative error below 1.2e-9),
// a polynomial ratio in the centre and one in sqrt(-2 log p) in the tails (p < 0.02425 or p > 0.97575).
double NormalQuantile(double p) {
  constexpr double a0 = -3.969683028665376e+01, a1 = 2.209460984245205e+02, a2 = -2.759285104469687e+02,
                   a3 = 1.383577518672690e+02, a4 = -3.066479806614716e+01, a5 = 2.506628277459239e+00;
  constexpr double b0 = -5.447609879822406e+01, b1 = 1.615858368580409e+02, b2 = -1.556989798598866e+02,
                   b3 = 6.680131188771972e+01, b4 = -1.328068155288572e+01;
  constexpr double c0 = -7.784894002430293e-03, c1 = -3.223964580411365e-01, c2 = -2.400758277161838e+00,
                   c3 = -2.549732539343734e+00, c4 = 4.374664141464968e+00, c5 = 2.938163982698783e+00;
  constexpr double d0 = 7.784695709041462e-03, d1 = 3.224671290700398e-01, d2 = 2.445134137142996e+00,
                   d3 = 3.754408661907416e+00;
  constexpr double low = 0.02425;
  if (p >= low && p <= 1 - low) {
    const double q = p - 0.5, r = q * q;
    return (((((a0 * r + a1) * r + a2) * r + a3) * r + a4) * r + a5) * q /
           (((((b0 * r + b1) * r + b2) * r + b3) * r + b4) * r + 1);
  }
  const double q = std::sqrt(-2 * std::log(p < low ? p : 1 - p));
  const double x = (((((c0 * q + c1) * q + c2) * q + c3) * q + c4) * q + c5) / ((((d0 * q + d1) * q + d2) * q + d3) * q + 1);
  return p < low ? x : -x;
}

// The h-th uniform of a SplitMix64 stream starting at `stream`, in (0, 1) (never 0 or 1).
double StreamUniform(uint64_t stream, uint64_t h) {
  return (static_cast<double>(SplitMix(stream + h * 0x9E3779B97F4A7C15ull) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

}  // namespace

PixelBuffer ApplySensor(const Frame& f, const SensorOptions& s, uint64_t seed, int* channels) {
  s.Check("sensor");
  *channels = s.bayer ? 1 : 3;
  const int C = *channels;
  PixelBuffer out(static_cast<size_t>(f.width) * f.height * C);  // every element written below
  // Vignetting: cos^4 falloff reaching 1 - v at the corner; cos(atan(t))^4 = 1 / (1 + t^2)^2 with
  // t = k r / corner, r the distance from the image centre.
  const double k = s.vignetting > 0 ? std::tan(std::acos(std::pow(1.0 - s.vignetting, 0.25))) : 0.0;
  const double cx = 0.5 * (f.width - 1), cy = 0.5 * (f.height - 1);
  const double k2 = k > 0 && cx + cy > 0 ? k * k / (cx * cx + cy * cy) : 0.0;
  // Noise: value i of the output (pixel * C + channel) draws from its own place in one SplitMix64 stream
  // (uniforms 2 i and 2 i + 1), so the result depends on the seed alone, not on how rows are shared among threads.
  // Above 20 electrons shot noise is Gaussian, and with the Gaussian read noise one normal of variance
  // e + read_noise^2; below, a Poisson count (by inversion) plus the read noise.
  const uint64_t stream = SplitMix(seed ^ 0xA5A5A5A5ull);
  const double read2 = s.read_noise * s.read_noise;
  tbb::parallel_for(tbb::blocked_range<int>(0, f.height, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      const double dy2 = (y - cy) * (y - cy);
      for (int x = 0; x < f.width; ++x) {
        const double t2 = k2 * ((x - cx) * (x - cx) + dy2);
        const double vig = 1.0 / ((1.0 + t2) * (1.0 + t2));
        const size_t p = static_cast<size_t>(y) * f.width + x;
        const auto sensor_value = [&](int ch, size_t i) {
          double v = f.rgb[3 * p + ch] * s.gain * vig;
          if (s.full_well > 0) {
            const double e = std::max(0.0, v * s.full_well);
            double noisy;
            if (e >= 20) {
              noisy = e + std::sqrt(e + read2) * NormalQuantile(StreamUniform(stream, 2 * i));
            } else {
              int count = 0;
              if (e > 0) {   // Poisson(e): the smallest count whose cumulative probability reaches u
                const double u = StreamUniform(stream, 2 * i);
                double term = std::exp(-e), cdf = term;
                while (u > cdf && count < 200) term *= e / ++count, cdf += term;
              }
              noisy = count + (s.read_noise > 0 ? s.read_noise * NormalQuantile(StreamUniform(stream, 2 * i + 1)) : 0.0);
            }
            v = noisy / s.full_well;
          }
          return static_cast<float>(std::clamp(v, 0.0, 1.0));
        };
        if (s.bayer) {
          const int ch = (y % 2 == 0) ? (x % 2 == 0 ? 0 : 1) : (x % 2 == 0 ? 1 : 2);  // RGGB
          out[p] = sensor_value(ch, p);
        } else {
          for (int ch = 0; ch < 3; ++ch) out[3 * p + ch] = sensor_value(ch, 3 * p + ch);
        }
      }
    }
  });
  return out;
}

void WriteGroundTruthExr(const std::filesystem::path& path, const Frame& frame,
                         const std::vector<std::pair<std::string, std::string>>& metadata) {
  HOVS_REQUIRE(!frame.truth.data.empty(), path.string(), "the frame has no ground truth");
  std::vector<std::pair<std::string, std::string>> attributes;
  for (const auto& [k, v] : metadata) attributes.emplace_back("hovs:" + k, v);
  io::WriteExr(path, frame.width, frame.height,
               std::vector<std::string>(GroundTruth::kNames, GroundTruth::kNames + GroundTruth::kChannels),
               frame.truth.data.data(), attributes);
}

std::map<std::string, std::string> RaytraceVersions() {
  std::map<std::string, std::string> v = io::IoVersions();
  v["embree"] = RTC_VERSION_STRING;
  return v;
}

}  // namespace hovs::raytrace
