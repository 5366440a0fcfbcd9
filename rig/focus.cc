#include "rig/focus.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/format.h"
#include "design/optics_report.h"

namespace hovs::rig {

namespace {

// Band sums of squared gradients and pixel counts; band kFocusBands: the whole annulus.
std::vector<double> BandMeans(const TurretImage& image, const TurretSpec& spec, int k, bool bands) {
  const PinholeCamera<double> cam = spec.ImageCamera();
  HOVS_REQUIRE(image.width == cam.width && image.height == cam.height, "sharpness", "image is ", image.width, "x",
               image.height, " but the camera is ", cam.width, "x", cam.height);
  const cv::Mat grey(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.grey.data()));
  cv::Mat f, gx, gy;
  grey.convertTo(f, CV_32F);
  cv::GaussianBlur(f, f, cv::Size(0, 0), 1.0);
  cv::Sobel(f, gx, CV_32F, 1, 0);
  cv::Sobel(f, gy, CV_32F, 0, 1);
  const TurretMirror& m = spec.mirrors.at(k);
  const double rim = cam.fx * m.mirror.RimRadius() / m.PlateHeight();
  const double r0 = 0.35 * rim, r1 = 0.95 * rim;
  const int n_bands = bands ? kFocusBands : 1;
  std::vector<double> sum(n_bands, 0.0);
  std::vector<long> n(n_bands, 0);
  for (int v = 0; v < image.height; ++v) {
    const float* px = gx.ptr<float>(v);
    const float* py = gy.ptr<float>(v);
    for (int u = 0; u < image.width; ++u) {
      const double r = std::hypot(u - cam.cx, v - cam.cy);
      if (r < r0 || r > r1) continue;
      const int b = std::min(n_bands - 1, static_cast<int>((r - r0) / (r1 - r0) * n_bands));
      sum[b] += double(px[u]) * px[u] + double(py[u]) * py[u];
      ++n[b];
    }
  }
  for (int b = 0; b < n_bands; ++b) sum[b] = n[b] > 0 ? sum[b] / n[b] : 0.0;
  return sum;
}

}  // namespace

std::vector<double> BandSharpness(const TurretImage& image, const TurretSpec& spec, int k) {
  return BandMeans(image, spec, k, true);
}

double Sharpness(const TurretImage& image, const TurretSpec& spec, int k) {
  return BandMeans(image, spec, k, false)[0];
}

void FocusOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(low) && std::isfinite(high) && low > 0 && low < high, where,
               "the bracket [low, high] must be positive with low < high");
  HOVS_REQUIRE(coarse_steps >= 3 && coarse_steps <= 1000, where, "coarse_steps must be 3..1000");
  HOVS_REQUIRE(refine_iterations >= 0 && refine_iterations <= 60, where, "refine_iterations must be 0..60");
  HOVS_REQUIRE(settle_timeout > 0, where, "settle_timeout must be positive");
}

FocusResult FocusLens(Plant& plant, const TurretSpec& spec, const FocusOptions& o) {
  o.Check("focus options");
  const int k = plant.Mirror();
  const AxisSpec& axis = spec.axes[static_cast<int>(AxisId::kFocus)];
  const double h = spec.mirrors.at(k).PlateHeight();
  const double lo = std::max(axis.min, o.low * h), hi = std::min(axis.max, o.high * h);
  HOVS_REQUIRE(lo < hi, "axis focus", "the focus bracket ", o.low * h, " .. ", o.high * h,
               " m lies outside the axis' travel");
  FocusResult r;
  const auto observe = [&](double f) {
    plant.machine().axis(AxisId::kFocus).MoveTo(f);
    plant.machine().WaitIdle(o.settle_timeout);
    ++r.images;
    return BandSharpness(plant.Observe(), spec, k);
  };
  // The coarse scan, then each band's best over it: the scale of the scores.
  std::vector<double> fs, reported;
  std::vector<std::vector<double>> bands;
  for (int i = 0; i < o.coarse_steps; ++i) {
    fs.push_back(lo + (hi - lo) * i / (o.coarse_steps - 1));
    bands.push_back(observe(fs.back()));
    reported.push_back(plant.machine().axis(AxisId::kFocus).Reported());
  }
  std::vector<double> best_band(kFocusBands, 0.0), mean(fs.size(), 0.0);
  for (size_t i = 0; i < fs.size(); ++i)
    for (int b = 0; b < kFocusBands; ++b) {
      best_band[b] = std::max(best_band[b], bands[i][b]);
      mean[i] += bands[i][b] / kFocusBands;
    }
  const double top = *std::max_element(mean.begin(), mean.end()), floor = *std::min_element(mean.begin(), mean.end());
  HOVS_REQUIRE(top > 1.2 * floor && *std::min_element(best_band.begin(), best_band.end()) > 0, "axis focus",
               "the mirror image's sharpness does not change over the focus ", lo, " .. ", hi, " m (", floor, " .. ",
               top, "): no structure to focus on, or the focus is stuck");
  const auto score_of = [&](const std::vector<double>& v) {
    double s = HUGE_VAL;
    for (int b = 0; b < kFocusBands; ++b) s = std::min(s, v[b] / best_band[b]);
    return s;
  };
  std::vector<double> ss;
  for (size_t i = 0; i < fs.size(); ++i) {
    ss.push_back(score_of(bands[i]));
    r.samples.emplace_back(reported[i], ss.back());
  }
  const auto measure = [&](double f) {
    const double s = score_of(observe(f));
    r.samples.emplace_back(plant.machine().axis(AxisId::kFocus).Reported(), s);
    return s;
  };
  const size_t best = std::max_element(ss.begin(), ss.end()) - ss.begin();
  // Golden-section search between the coarse maximum's neighbours.
  double a = fs[best > 0 ? best - 1 : 0], b = fs[std::min(best + 1, fs.size() - 1)];
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double c = b - g * (b - a), d = a + g * (b - a);
  double sc = measure(c), sd = measure(d);
  for (int i = 0; i < o.refine_iterations; ++i) {
    if (sc >= sd) {
      b = d, d = c, sd = sc;
      c = b - g * (b - a);
      sc = measure(c);
    } else {
      a = c, c = d, sc = sd;
      d = a + g * (b - a);
      sd = measure(d);
    }
  }
  // Leave the axis at the best focus seen (the coarse maximum if the refinement found nothing better).
  const auto top_sample = std::max_element(r.samples.begin(), r.samples.end(),
                                           [](const auto& x, const auto& y) { return x.second < y.second; });
  const double best_focus = top_sample->first;
  const std::vector<double> last = observe(best_focus);
  r.score = score_of(last);
  r.samples.emplace_back(plant.machine().axis(AxisId::kFocus).Reported(), r.score);
  double mean_last = 0;
  for (const double v : last) mean_last += v / kFocusBands;
  r.sharpness = mean_last;
  r.focus = plant.machine().axis(AxisId::kFocus).Reported();
  return r;
}

std::optional<PredictedFocus> PredictFocus(const TurretSpec& spec, int k) {
  if (!spec.lens) return std::nullopt;
  const TurretMirror& m = spec.mirrors.at(k);
  design::DesignProblem problem;
  problem.camera.focal_length = spec.lens->focal_length;
  problem.camera.pixel_pitch = spec.pixel_pitch;
  problem.camera.width = spec.camera.width, problem.camera.height = spec.camera.height;
  problem.camera.lens_aperture = spec.lens_aperture;
  problem.camera.lens = *spec.lens;
  problem.camera.lens.focus_distance = std::numeric_limits<double>::infinity();
  const design::FocusPrediction f = design::PredictFocus({m.mirror.a, m.mirror.b, m.mirror.rim_diameter}, problem);
  PredictedFocus out;
  out.best = f.best.focus_distance, out.near = f.depth.near_focus, out.far = f.depth.far_focus;
  out.worst_rms_px = f.best.worst_rms, out.tolerance_px = f.depth.tolerance_px;
  return out;
}

std::string FocusAgainstPrediction(const TurretSpec& spec, int k, double focus) {
  const auto p = PredictFocus(spec, k);
  if (!p) return "";
  return " (predicted best " + FormatNumber("%.4f", p->best) + " m, depth of focus " + FormatNumber("%.4f", p->near) +
         " .. " + (std::isinf(p->far) ? std::string("inf") : FormatNumber("%.4f", p->far)) +
         " m: " + (p->Contains(focus) ? "within" : "OUTSIDE") + ")";
}

}  // namespace hovs::rig
