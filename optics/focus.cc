#include "optics/focus.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace hovs::optics {
namespace {

double FromVergence(double v) { return v > 0 ? 1.0 / v : kInfinity; }

Spot SpotAtVergence(const OpticalSystem& sys, const Bundle& b, double v) {
  const double d = FromVergence(v);
  return SpotAt(b, sys.CameraAt(d), d);
}

// The minimum of f on [0, v_max]: a scan of n points, then golden-section search about the best of them.
template <class F>
double MinimiseVergence(const F& f, double v_max, int n = 48) {
  int best = 0;
  double best_value = HUGE_VAL;
  for (int k = 0; k <= n; ++k) {
    const double value = f(v_max * k / n);
    if (value < best_value) best_value = value, best = k;
  }
  double lo = v_max * std::max(best - 1, 0) / n, hi = v_max * std::min(best + 1, n) / n;
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < 60 && hi - lo > 1e-9 * (1 + v_max); ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = f(x2);
    }
  }
  const double v = 0.5 * (lo + hi);
  return f(v) <= best_value ? v : v_max * best / n;
}

}  // namespace

std::vector<TracedField> TraceFields(const OpticalSystem& sys, const std::vector<FieldPoint>& fields) {
  std::vector<TracedField> out(fields.size());
  const std::vector<double> pupil = PupilPoints(sys.pupil_samples, sys.lens.ApertureRadius());
  tbb::parallel_for(size_t(0), fields.size(), [&](size_t i) {
    out[i].field = fields[i];
    out[i].bundle = TraceBundle(sys.rig, fields[i].Position(), sys.lens.ApertureRadius(), pupil);
  });
  return out;
}

std::vector<FocusSample> ThroughFocus(const OpticalSystem& sys, const Bundle& b, const std::vector<double>& focus) {
  std::vector<FocusSample> out;
  for (const double d : focus) {
    const Spot s = SpotAt(b, sys.CameraAt(d), d);
    out.push_back({d, s.rms, s.radial_rms, s.tangential_rms});
  }
  return out;
}

BestFocus BestFocusOf(const OpticalSystem& sys, const Bundle& b, double min_focus) {
  BestFocus out;
  if (b.Empty()) return out;
  const double v_max = 1.0 / min_focus;
  const double v_rms = MinimiseVergence([&](double v) { return SpotAtVergence(sys, b, v).rms; }, v_max);
  const double v_rad = MinimiseVergence([&](double v) { return SpotAtVergence(sys, b, v).radial_rms; }, v_max);
  const double v_tan = MinimiseVergence([&](double v) { return SpotAtVergence(sys, b, v).tangential_rms; }, v_max);
  out.rms_focus = FromVergence(v_rms), out.radial_focus = FromVergence(v_rad),
  out.tangential_focus = FromVergence(v_tan);
  out.rms = SpotAtVergence(sys, b, v_rms).rms;
  return out;
}

namespace {

// The largest RMS radius over the fields' bundles at vergence v; *where: its field.
double WorstRmsAt(const OpticalSystem& sys, const std::vector<TracedField>& fields, double v, size_t* where) {
  double w = 0;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (fields[i].bundle.Empty()) continue;
    const double r = SpotAtVergence(sys, fields[i].bundle, v).rms;
    if (r > w) w = r, *where = i;
  }
  return w;
}

}  // namespace

SingleFocus BestSingleFocus(const OpticalSystem& sys, const std::vector<TracedField>& fields, double min_focus) {
  SingleFocus out;
  const auto worst = [&](double v, size_t* where) { return WorstRmsAt(sys, fields, v, where); };
  size_t where = 0;
  const double v = MinimiseVergence([&](double x) { return worst(x, &where); }, 1.0 / min_focus, 96);
  out.focus_distance = FromVergence(v);
  out.worst_rms = worst(v, &where);
  out.worst_field = where;
  return out;
}

DepthOfFocus DepthOfFocusOf(const OpticalSystem& sys, const std::vector<TracedField>& fields, const SingleFocus& best,
                            double tolerance_px, double min_focus) {
  DepthOfFocus out;
  out.best_focus = best.focus_distance, out.best_worst_rms = best.worst_rms, out.tolerance_px = tolerance_px;
  const double limit = best.worst_rms + tolerance_px, v_best = best.focus_distance > 0 ? 1.0 / best.focus_distance : 0;
  size_t where = 0;
  const auto within = [&](double v) { return WorstRmsAt(sys, fields, v, &where) <= limit; };
  // Bisect the crossing between a vergence within the limit and one beyond it.
  const auto crossing = [&](double v_in, double v_out) {
    for (int it = 0; it < 50; ++it) {
      const double m = 0.5 * (v_in + v_out);
      (within(m) ? v_in : v_out) = m;
    }
    return v_in;
  };
  const double v_max = 1.0 / min_focus;
  out.near_focus = FromVergence(within(v_max) ? v_max : crossing(v_best, v_max));
  out.far_focus = within(0) ? kInfinity : FromVergence(crossing(v_best, 0));
  return out;
}

DepthOfField DepthOfFieldAt(const OpticalSystem& sys, double elevation_deg, double focus_distance, double limit_px,
                            double min_distance) {
  DepthOfField out;
  out.elevation_deg = elevation_deg;
  const std::vector<double> pupil = PupilPoints(sys.pupil_samples, sys.lens.ApertureRadius());
  const PinholeCamera<double> cam = sys.CameraAt(focus_distance);
  // RMS radius of the point at distance 1 / q from F1 (q = 0: at infinity).
  const auto rms = [&](double q) {
    const FieldPoint f{elevation_deg, 0, q > 0 ? 1.0 / q : kInfinity};
    const Bundle b = TraceBundle(sys.rig, f.Position(), sys.lens.ApertureRadius(), pupil);
    const Spot s = SpotAt(b, cam, focus_distance);
    return s.Valid() ? s.rms : HUGE_VAL;
  };
  const int n = 64;
  const double q_max = 1.0 / min_distance;
  std::vector<double> r(n + 1);
  for (int k = 0; k <= n; ++k) r[k] = rms(q_max * k / n);
  const int best = static_cast<int>(std::min_element(r.begin(), r.end()) - r.begin());
  if (!(r[best] <= limit_px)) {
    out.near = out.far = std::nan("");
    return out;
  }
  out.sharp = true;
  // Bisect the crossing of the limit between a sharp q and a blurred one.
  const auto crossing = [&](double q_sharp, double q_blur) {
    for (int it = 0; it < 40; ++it) {
      const double m = 0.5 * (q_sharp + q_blur);
      (rms(m) <= limit_px ? q_sharp : q_blur) = m;
    }
    return q_sharp;
  };
  int k = best;
  while (k < n && r[k + 1] <= limit_px) ++k;
  const double q_near = k == n ? q_max : crossing(q_max * k / n, q_max * (k + 1) / n);
  k = best;
  while (k > 0 && r[k - 1] <= limit_px) --k;
  const double q_far = k == 0 ? 0.0 : crossing(q_max * k / n, q_max * (k - 1) / n);
  out.near = 1.0 / q_near;
  out.far = q_far > 0 ? 1.0 / q_far : kInfinity;
  return out;
}

std::vector<FieldPoint> FieldGrid(double lower_deg, double upper_deg, int n_elevation,
                                  const std::vector<double>& distances) {
  std::vector<FieldPoint> out;
  for (int i = 0; i < n_elevation; ++i) {
    const double e = lower_deg + (upper_deg - lower_deg) * (i + 0.5) / n_elevation;
    for (const double d : distances) out.push_back({e, 0, d});
  }
  return out;
}

std::vector<double> DistanceGrid(double near, double far, int n) {
  std::vector<double> out;
  for (int k = 0; k + 1 < n; ++k)
    out.push_back(n == 2 ? near : near * std::pow(far / near, double(k) / std::max(n - 2, 1)));
  out.push_back(kInfinity);
  return out;
}

std::vector<FieldBlur> Atlas(const OpticalSystem& sys, const std::vector<FieldPoint>& fields, double focus_distance) {
  std::vector<FieldBlur> out(fields.size());
  const std::vector<double> pupil = PupilPoints(sys.pupil_samples, sys.lens.ApertureRadius());
  tbb::parallel_for(size_t(0), fields.size(), [&](size_t i) {
    const Bundle b = TraceBundle(sys.rig, fields[i].Position(), sys.lens.ApertureRadius(), pupil);
    out[i] = BlurOf(sys, fields[i], b, focus_distance);
  });
  return out;
}

}  // namespace hovs::optics
