#include "calib/edge_curve.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace hovs::calib {

std::optional<double> SampleGrey(const cv::Mat& g, double u, double v) {
  if (!(u >= 0 && v >= 0 && u <= g.cols - 1.001 && v <= g.rows - 1.001)) return std::nullopt;
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const double fx = u - x, fy = v - y;
  const uint8_t* r0 = g.ptr<uint8_t>(y) + x;
  const uint8_t* r1 = g.ptr<uint8_t>(y + 1) + x;
  return (r0[0] * (1 - fx) + r0[1] * fx) * (1 - fy) + (r1[0] * (1 - fx) + r1[1] * fx) * fy;
}

double EdgeCurve::Offset(double t) const {
  const double s = t / len - 0.5;
  double f = 0, sk = 1;
  for (int k = 0; k < coef.size(); ++k) f += coef[k] * sk, sk *= s;
  return f;
}

double EdgeCurve::Slope(double t) const {
  const double s = t / len - 0.5;
  double d = 0, sk = 1;
  for (int k = 1; k < coef.size(); ++k) d += k * coef[k] * sk, sk *= s;
  return d / len;
}

namespace {

Eigen::VectorXd FitPoly(const std::vector<double>& s, const std::vector<double>& f, const std::vector<char>& use,
                        int degree) {
  int m = 0;
  for (char u : use) m += u;
  Eigen::MatrixXd A(m, degree + 1);
  Eigen::VectorXd b(m);
  int r = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!use[i]) continue;
    double sk = 1;
    for (int k = 0; k <= degree; ++k) A(r, k) = sk, sk *= s[i];
    b(r++) = f[i];
  }
  return A.colPivHouseholderQr().solve(b);
}

// The edge's offset within a profile from dark to bright sampled every `step` px from -half: the area of the
// profile's dark fraction (trapezoid rule). Only the step itself counts: beyond the first sample that is back
// at the dark level (towards the dark side) or at the bright level (towards the bright side) the profile is
// taken as flat, so a narrow white margin with the scene behind it, the next square of a checkerboard or an
// inner bit of a marker squeezed by the mirror does not move the edge. nullopt without a crossing of the mid
// level.
std::optional<double> EdgeByArea(const std::vector<double>& prof, double dark, double bright, double half,
                                 double step) {
  const int np = static_cast<int>(prof.size());
  const double contrast = bright - dark, mid = 0.5 * (dark + bright);
  int cross = -1;  // the crossing nearest the profile's centre: between cross and cross + 1
  for (int i = 0; i + 1 < np; ++i)
    if (prof[i] < mid && prof[i + 1] >= mid &&
        (cross < 0 || std::abs(i - (np - 1) / 2) < std::abs(cross - (np - 1) / 2)))
      cross = i;
  if (cross < 0) return std::nullopt;
  std::vector<double> f(np);
  for (int i = 0; i < np; ++i) f[i] = std::clamp((bright - prof[i]) / contrast, 0.0, 1.0);
  bool flat = false;
  for (int i = cross; i >= 0; --i) {
    if (flat) f[i] = 1;
    flat = flat || prof[i] <= dark + 0.1 * contrast;
  }
  flat = false;
  for (int i = cross + 1; i < np; ++i) {
    if (flat) f[i] = 0;
    flat = flat || prof[i] >= bright - 0.1 * contrast;
  }
  double area = 0;
  for (int i = 0; i + 1 < np; ++i) area += 0.5 * (f[i] + f[i + 1]) * step;
  return -half + area;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

std::optional<EdgeCurve> MeasureEdgeCurve(const cv::Mat& g, const Vec2d& p, const Vec2d& e, double len,
                                          const std::vector<EdgeStretch>& stretches, const EdgeCurveOptions& o) {
  if (g.empty() || g.type() != CV_8UC1 || !(len > 0)) return std::nullopt;
  EdgeCurve fit;
  fit.p = p, fit.e = e.normalized(), fit.len = len;
  fit.n = Vec2d(-fit.e.y(), fit.e.x());
  const double half = o.half_profile, step = 0.25;
  const int np = static_cast<int>(std::lround(2 * half / step)) + 1;
  // A profile across the edge at t, centred at offset `centre`, always from the dark to the bright side.
  const auto profile = [&](double t, double centre, double sg, std::vector<double>* prof) {
    prof->resize(np);
    for (int i = 0; i < np; ++i) {
      const Vec2d q = p + t * fit.e + (centre + sg * (-half + i * step)) * fit.n;
      const auto v = SampleGrey(g, q.x(), q.y());
      if (!v) return false;
      (*prof)[i] = *v;
    }
    return true;
  };
  // Pass 1: track along each stretch (each profile centred where the edge found so far predicts it: the edge
  // bends), with each profile's own dark and bright levels.
  std::vector<double> ts, offs, darks, brights;
  std::vector<int> which;  // stretch of each point
  std::vector<double> prof;
  int expected = 0;
  for (size_t k = 0; k < stretches.size(); ++k) {
    const auto& st = stretches[k];
    const double sg = st.dark_on_minus_n ? 1 : -1, dir = st.to >= st.from ? 1 : -1;
    const int steps = static_cast<int>(std::floor(std::abs(st.to - st.from) + 1e-9)) + 1;
    expected += steps;
    std::vector<double> kt, ko;
    for (int i = 0; i < steps; ++i) {
      const double t = st.from + dir * i;
      double centre = 0;
      if (ko.size() >= 2) {
        const size_t m = ko.size();
        centre = ko[m - 1] + (ko[m - 1] - ko[m - 2]) * (t - kt[m - 1]) / (kt[m - 1] - kt[m - 2]);
      } else if (ko.size() == 1) {
        centre = ko[0];
      }
      if (!profile(t, centre, sg, &prof)) continue;
      // Levels: the darkest sample of the dark half and the brightest of the bright half.
      const double dark = *std::min_element(prof.begin(), prof.begin() + np / 2);
      const double bright = *std::max_element(prof.begin() + np / 2, prof.end());
      if (bright - dark < o.min_contrast) continue;
      const auto off = EdgeByArea(prof, dark, bright, half, step);
      if (!off || std::abs(*off) > half - 0.5) continue;  // the edge is not inside this profile
      kt.push_back(t), ko.push_back(centre + sg * *off);
      ts.push_back(t), offs.push_back(ko.back()), darks.push_back(dark), brights.push_back(bright);
      which.push_back(static_cast<int>(k));
    }
  }
  const int n = static_cast<int>(ts.size());
  if (n < 6 || n < o.min_coverage * expected) return std::nullopt;
  std::vector<double> s(n);
  for (int i = 0; i < n; ++i) s[i] = ts[i] / fit.len - 0.5;
  std::vector<char> use(n, 1);
  // A quadratic offset from the chord unless a cubic is clearly better: where a corner lies beyond the data, a
  // needless cubic term costs accuracy (rendered markers, the data stopping a cell short of the corners:
  // 0.047 px RMS with quadratics, 0.103 px with cubics).
  const auto sum_sq = [&](int degree) {
    fit.coef = FitPoly(s, offs, use, degree);
    double ss = 0;
    for (int i = 0; i < n; ++i) ss += std::pow(offs[i] - fit.Offset(ts[i]), 2);
    return ss;
  };
  const int degree = n >= 12 && n * std::log(sum_sq(2) / std::max(sum_sq(3), 1e-12)) > 20 ? 3 : 2;
  fit.coef = FitPoly(s, offs, use, degree);
  // Pass 2: every profile centred on the fitted edge, with its stretch's median levels (less noise than each
  // profile's ends).
  std::vector<double> dark(stretches.size(), 0), bright(stretches.size(), 0);
  for (size_t k = 0; k < stretches.size(); ++k) {
    std::vector<double> d, b;
    for (int i = 0; i < n; ++i)
      if (which[i] == static_cast<int>(k)) d.push_back(darks[i]), b.push_back(brights[i]);
    if (!d.empty()) dark[k] = Median(d), bright[k] = Median(b);
  }
  for (int i = 0; i < n; ++i) {
    const double centre = fit.Offset(ts[i]), sg = stretches[which[i]].dark_on_minus_n ? 1 : -1;
    const auto off = profile(ts[i], centre, sg, &prof) ? EdgeByArea(prof, dark[which[i]], bright[which[i]], half, step)
                                                       : std::nullopt;
    if (off)
      offs[i] = centre + sg * *off;
    else
      use[i] = 0;
  }
  fit.coef = FitPoly(s, offs, use, degree);
  // One round of outlier rejection (a target partly hidden, a stray edge), then the final fit.
  std::vector<double> absr;
  for (int i = 0; i < n; ++i)
    if (use[i]) absr.push_back(std::abs(offs[i] - fit.Offset(ts[i])));
  if (absr.size() < 6) return std::nullopt;
  const double sigma = 1.4826 * Median(absr);
  int kept = 0;
  for (int i = 0; i < n; ++i)
    kept += use[i] = use[i] && std::abs(offs[i] - fit.Offset(ts[i])) <= std::max(3 * sigma, 0.15);
  if (kept < std::max(6, static_cast<int>(0.7 * n))) return std::nullopt;
  fit.coef = FitPoly(s, offs, use, degree);
  double ss = 0;
  for (int i = 0; i < n; ++i) {
    if (!use[i]) continue;
    const double r = offs[i] - fit.Offset(ts[i]);
    ss += r * r;
  }
  fit.fit_rms = std::sqrt(ss / kept);
  fit.points = kept;
  if (fit.fit_rms > o.max_fit_rms_px) return std::nullopt;
  return fit;
}

std::optional<Vec2d> IntersectEdgeCurves(const EdgeCurve& a, double ta0, const EdgeCurve& b, double tb0) {
  double ta = ta0, tb = tb0;
  for (int it = 0; it < 20; ++it) {
    const Vec2d r = a.At(ta) - b.At(tb);
    Eigen::Matrix2d J;
    J.col(0) = a.Tangent(ta);
    J.col(1) = -b.Tangent(tb);
    if (std::abs(J.determinant()) < 1e-3) return std::nullopt;  // (nearly) parallel
    const Eigen::Vector2d d = J.lu().solve(-r);
    ta += d(0), tb += d(1);
    if (d.norm() < 1e-9) break;
  }
  if (std::abs(ta - ta0) > 0.5 * a.len || std::abs(tb - tb0) > 0.5 * b.len) return std::nullopt;
  return a.At(ta);
}

}  // namespace hovs::calib
