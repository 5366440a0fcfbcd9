#include "rig/focus.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>

#include "core/error.h"
#include "core/format.h"
#include "design/optics_report.h"

namespace hovs::rig {

double Sharpness(const TurretImage& image, const TurretSpec& spec, int k) {
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
  double sum = 0;
  long n = 0;
  for (int v = 0; v < image.height; ++v) {
    const float* px = gx.ptr<float>(v);
    const float* py = gy.ptr<float>(v);
    for (int u = 0; u < image.width; ++u) {
      const double r = std::hypot(u - cam.cx, v - cam.cy);
      if (r < r0 || r > r1) continue;
      sum += double(px[u]) * px[u] + double(py[u]) * py[u];
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
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
  const auto measure = [&](double f) {
    plant.machine().axis(AxisId::kFocus).MoveTo(f);
    plant.machine().WaitIdle(o.settle_timeout);
    const double s = Sharpness(plant.Observe(), spec, k);
    ++r.images;
    r.samples.emplace_back(plant.machine().axis(AxisId::kFocus).Reported(), s);
    return s;
  };
  std::vector<double> fs, ss;
  for (int i = 0; i < o.coarse_steps; ++i) {
    fs.push_back(lo + (hi - lo) * i / (o.coarse_steps - 1));
    ss.push_back(measure(fs.back()));
  }
  const size_t best = std::max_element(ss.begin(), ss.end()) - ss.begin();
  const double floor = *std::min_element(ss.begin(), ss.end());
  HOVS_REQUIRE(ss[best] > 1.2 * floor, "axis focus", "the mirror image's sharpness does not change over the focus ", lo,
               " .. ", hi, " m (", floor, " .. ", ss[best], "): no structure to focus on, or the focus is stuck");
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
  const auto top = std::max_element(r.samples.begin(), r.samples.end(),
                                    [](const auto& x, const auto& y) { return x.second < y.second; });
  const double best_focus = top->first;
  r.sharpness = measure(best_focus);
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
  // A study reports the prediction with every run of a mirror: each distinct mirror and lens is traced once.
  const std::array<double, 9> key = {m.mirror.a,
                                     m.mirror.b,
                                     m.mirror.rim_diameter,
                                     spec.lens->focal_length,
                                     spec.lens->f_number,
                                     spec.lens->wavelength,
                                     spec.pixel_pitch,
                                     spec.lens_aperture,
                                     double(spec.camera.width) * 1e5 + spec.camera.height};
  static std::mutex mutex;
  static std::map<std::array<double, 9>, PredictedFocus> known;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = known.find(key); it != known.end()) return it->second;
  }
  const design::FocusPrediction f = design::PredictFocus({m.mirror.a, m.mirror.b, m.mirror.rim_diameter}, problem);
  PredictedFocus out;
  out.best = f.best.focus_distance, out.near = f.depth.near_focus, out.far = f.depth.far_focus;
  out.worst_rms_px = f.best.worst_rms, out.tolerance_px = f.depth.tolerance_px;
  const std::lock_guard<std::mutex> lock(mutex);
  known.emplace(key, out);
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
