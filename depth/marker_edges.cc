#include "depth/marker_edges.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace hovs::depth {
namespace {

// Bilinear grey value at (u, v); nullopt outside the image.
std::optional<double> Sample(const cv::Mat& g, double u, double v) {
  if (!(u >= 0 && v >= 0 && u <= g.cols - 1.001 && v <= g.rows - 1.001)) return std::nullopt;
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const double fx = u - x, fy = v - y;
  const uint8_t* r0 = g.ptr<uint8_t>(y) + x;
  const uint8_t* r1 = g.ptr<uint8_t>(y + 1) + x;
  return (r0[0] * (1 - fx) + r0[1] * fx) * (1 - fy) + (r1[0] * (1 - fx) + r1[1] * fx) * fy;
}

// A side measured and fitted: point(t) = p + t e + f(t) n, f a polynomial in s = t / len - 0.5.
struct SideFit {
  Vec2d p, e, n;
  double len = 0;
  Eigen::VectorXd coef;   // f(s) = sum coef[k] s^k
  double Offset(double t) const {
    const double s = t / len - 0.5;
    double f = 0, sk = 1;
    for (int k = 0; k < coef.size(); ++k) f += coef[k] * sk, sk *= s;
    return f;
  }
  double Slope(double t) const {   // df/dt
    const double s = t / len - 0.5;
    double d = 0, sk = 1;
    for (int k = 1; k < coef.size(); ++k) d += k * coef[k] * sk, sk *= s;
    return d / len;
  }
  Vec2d At(double t) const { return p + t * e + Offset(t) * n; }
  Vec2d Tangent(double t) const { return e + Slope(t) * n; }
};

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

// The edge's offset within a profile from dark (inside) to bright (outside) sampled every `step` px from
// -half: the area of the profile's dark fraction (trapezoid rule), which any symmetric blur and the pixels'
// own integration preserve; a threshold crossing of the interpolated profile would lock towards pixel
// centres (up to 0.08 px for a sharp edge along a pixel row). Only the step itself counts: beyond the first
// sample that is back at the dark level (inwards) or at the bright level (outwards) the profile is taken as
// flat, so a narrow white margin with the scene behind it, or an inner bit of a marker squeezed by the
// mirror, does not move the edge. nullopt without a crossing of the mid level.
std::optional<double> EdgeByArea(const std::vector<double>& prof, double dark, double bright, double half,
                                 double step) {
  const int np = static_cast<int>(prof.size());
  const double contrast = bright - dark, mid = 0.5 * (dark + bright);
  int cross = -1;   // the crossing nearest the profile's centre: between cross and cross + 1
  for (int i = 0; i + 1 < np; ++i)
    if (prof[i] < mid && prof[i + 1] >= mid && (cross < 0 || std::abs(i - (np - 1) / 2) < std::abs(cross - (np - 1) / 2)))
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

// Measures the side from a to b (the marker's centroid c tells inside from outside).
// across: the cell size across the side (the adjacent sides' length / cells; near the rim the mirror squeezes
// cells radially, so it can be much less than along the side).
std::optional<SideFit> MeasureSide(const cv::Mat& g, const Vec2d& a, const Vec2d& b, const Vec2d& c, double across,
                                   const MarkerEdgeOptions& o) {
  SideFit fit;
  fit.p = a;
  fit.len = (b - a).norm();
  const double cell = fit.len / o.cells;
  if (!(cell >= o.min_cell_px) || !(across >= o.min_cell_px)) return std::nullopt;
  fit.e = (b - a) / fit.len;
  fit.n = Vec2d(-fit.e.y(), fit.e.x());
  if (fit.n.dot(c - 0.5 * (a + b)) > 0) fit.n = -fit.n;   // n points out of the marker: dark -> bright
  const double half = std::clamp(0.45 * across, 1.0, 4.0), step = 0.25;
  const int np = static_cast<int>(std::lround(2 * half / step)) + 1;
  const auto profile = [&](double t, double centre, std::vector<double>* prof) {
    prof->resize(np);
    for (int i = 0; i < np; ++i) {
      const Vec2d q = a + t * fit.e + (centre - half + i * step) * fit.n;
      const auto v = Sample(g, q.x(), q.y());
      if (!v) return false;
      (*prof)[i] = *v;
    }
    return true;
  };
  // Pass 1: track along the side (each profile centred where the edge found so far predicts it: the side
  // bends), with each profile's own dark and bright levels.
  std::vector<double> ts, offs, darks, brights;
  std::vector<double> prof;
  const double end = std::max(2.0, 0.25 * cell);   // clear of the adjacent sides' edges (blur and the pixel)
  for (double t = end; t <= fit.len - end + 1e-9; t += 1.0) {
    double centre = 0;
    if (offs.size() >= 2) {
      const size_t k = offs.size();
      centre = offs[k - 1] + (offs[k - 1] - offs[k - 2]) * (t - ts[k - 1]) / (ts[k - 1] - ts[k - 2]);
    } else if (offs.size() == 1) {
      centre = offs[0];
    }
    if (!profile(t, centre, &prof)) continue;
    // Levels: the darkest sample of the inner half and the brightest of the outer half (a thin white margin
    // with the scene behind it may already fall off at the profile's outer end).
    const double dark = *std::min_element(prof.begin(), prof.begin() + np / 2);
    const double bright = *std::max_element(prof.begin() + np / 2, prof.end());
    if (bright - dark < o.min_contrast) continue;
    const auto off = EdgeByArea(prof, dark, bright, half, step);
    if (!off || std::abs(*off) > half - 0.5) continue;   // the edge is not inside this profile
    ts.push_back(t);
    offs.push_back(centre + *off);
    darks.push_back(dark), brights.push_back(bright);
  }
  const int n = static_cast<int>(ts.size());
  if (n < 6 || n < 0.6 * ((fit.len - 2 * end) + 1)) return std::nullopt;
  std::vector<double> s(n);
  for (int i = 0; i < n; ++i) s[i] = ts[i] / fit.len - 0.5;
  std::vector<char> use(n, 1);
  // A quadratic offset from the chord unless a cubic is clearly better (a long side near the image's
  // centre): the corner lies beyond the data, where a needless cubic term costs accuracy (rendered markers,
  // measured when the data stopped a cell short of the corners: 0.047 px RMS with quadratics, 0.103 px with
  // cubics).
  const auto sum_sq = [&](int degree) {
    fit.coef = FitPoly(s, offs, use, degree);
    double ss = 0;
    for (int i = 0; i < n; ++i) ss += std::pow(offs[i] - fit.Offset(ts[i]), 2);
    return ss;
  };
  const int degree = n >= 12 && n * std::log(sum_sq(2) / std::max(sum_sq(3), 1e-12)) > 20 ? 3 : 2;
  fit.coef = FitPoly(s, offs, use, degree);
  // Pass 2: every profile centred on the fitted edge, the side's median levels (less noise than each
  // profile's ends).
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double dark = median(darks), bright = median(brights);
  for (int i = 0; i < n; ++i) {
    const double centre = fit.Offset(ts[i]);
    const auto off = profile(ts[i], centre, &prof) ? EdgeByArea(prof, dark, bright, half, step) : std::nullopt;
    if (off) offs[i] = centre + *off;
    else use[i] = 0;
  }
  fit.coef = FitPoly(s, offs, use, degree);
  // One round of outlier rejection (a marker partly hidden, a stray edge), then the final fit.
  std::vector<double> absr;
  for (int i = 0; i < n; ++i)
    if (use[i]) absr.push_back(std::abs(offs[i] - fit.Offset(ts[i])));
  if (absr.size() < 6) return std::nullopt;
  const double sigma = 1.4826 * median(absr);
  int kept = 0;
  for (int i = 0; i < n; ++i) kept += use[i] = use[i] && std::abs(offs[i] - fit.Offset(ts[i])) <= std::max(3 * sigma, 0.15);
  if (kept < std::max(6, static_cast<int>(0.7 * n))) return std::nullopt;
  fit.coef = FitPoly(s, offs, use, degree);
  double ss = 0;
  for (int i = 0; i < n; ++i) {
    if (!use[i]) continue;
    const double r = offs[i] - fit.Offset(ts[i]);
    ss += r * r;
  }
  if (std::sqrt(ss / kept) > o.max_fit_rms_px) return std::nullopt;
  return fit;
}

// Intersection of side a near its end and side b near its start (Newton on the two parameters).
std::optional<Vec2d> Intersect(const SideFit& a, const SideFit& b) {
  double ta = a.len, tb = 0;
  for (int it = 0; it < 20; ++it) {
    const Vec2d r = a.At(ta) - b.At(tb);
    Eigen::Matrix2d J;
    J.col(0) = a.Tangent(ta);
    J.col(1) = -b.Tangent(tb);
    if (std::abs(J.determinant()) < 1e-3) return std::nullopt;   // (nearly) parallel sides
    const Eigen::Vector2d d = J.lu().solve(-r);
    ta += d(0), tb += d(1);
    if (d.norm() < 1e-9) break;
  }
  // The intersection must lie near the ends the fits describe.
  if (std::abs(ta - a.len) > 0.5 * a.len || std::abs(tb) > 0.5 * b.len) return std::nullopt;
  return a.At(ta);
}

}  // namespace

std::array<bool, 4> RefineMarkerCornersByEdges(const cv::Mat& grey, std::array<Vec2d, 4>* corners,
                                               const MarkerEdgeOptions& o) {
  std::array<bool, 4> refined{false, false, false, false};
  if (grey.empty() || grey.type() != CV_8UC1) return refined;
  const auto& c = *corners;
  const Vec2d centroid = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  std::array<std::optional<SideFit>, 4> sides;   // side k: corner k -> corner k + 1
  for (int k = 0; k < 4; ++k) {
    const double across = 0.5 * ((c[(k + 1) % 4] - c[(k + 2) % 4]).norm() + (c[(k + 3) % 4] - c[k]).norm()) / o.cells;
    sides[k] = MeasureSide(grey, c[k], c[(k + 1) % 4], centroid, across, o);
  }
  std::array<Vec2d, 4> out = c;
  for (int k = 0; k < 4; ++k) {
    const auto& a = sides[(k + 3) % 4];   // ends at corner k
    const auto& b = sides[k];             // starts at corner k
    if (!a || !b) continue;
    const auto p = Intersect(*a, *b);
    if (!p) continue;
    out[k] = *p;
    refined[k] = true;
  }
  *corners = out;
  return refined;
}

}  // namespace hovs::depth
