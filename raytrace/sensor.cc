#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "raytrace/render.h"
#include "raytrace/sampling.h"

namespace hovs::raytrace {

void SensorOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(gain) && gain > 0, where + ".gain", "must be positive");
  HOVS_REQUIRE(vignetting >= 0 && vignetting < 1, where + ".vignetting", "must be in [0, 1)");
  HOVS_REQUIRE(std::isfinite(full_well) && full_well >= 0, where + ".full_well", "must be >= 0");
  HOVS_REQUIRE(std::isfinite(read_noise) && read_noise >= 0, where + ".read_noise", "must be >= 0");
  HOVS_REQUIRE(read_noise == 0 || full_well > 0, where + ".read_noise", "needs full_well > 0");
  HOVS_REQUIRE(bit_depth == 8 || bit_depth == 16, where + ".bit_depth", "must be 8 or 16 (got ", bit_depth, ")");
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
  const double x =
      (((((c0 * q + c1) * q + c2) * q + c3) * q + c4) * q + c5) / ((((d0 * q + d1) * q + d2) * q + d3) * q + 1);
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
              if (e > 0) {  // Poisson(e): the smallest count whose cumulative probability reaches u
                const double u = StreamUniform(stream, 2 * i);
                double term = std::exp(-e), cdf = term;
                while (u > cdf && count < 200) term *= e / ++count, cdf += term;
              }
              noisy =
                  count + (s.read_noise > 0 ? s.read_noise * NormalQuantile(StreamUniform(stream, 2 * i + 1)) : 0.0);
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

}  // namespace hovs::raytrace
