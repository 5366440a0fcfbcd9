#include "optics/slanted_edge.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>

namespace hovs::optics {

EdgeMtf MeasureSlantedEdge(const std::vector<float>& grey, int w, int h, bool across_x) {
  EdgeMtf out;
  // In edge coordinates: n lines along the edge, m pixels across it; value(line, k).
  const int n = across_x ? h : w, m = across_x ? w : h;
  if (n < 16 || m < 16 || grey.size() < size_t(w) * h) return out;
  const auto value = [&](int line, int k) {
    return double(across_x ? grey[size_t(line) * w + k] : grey[size_t(k) * w + line]);
  };

  // Edge position in each line: the centroid of |derivative| (central differences).
  std::vector<double> lines, pos;
  for (int i = 0; i < n; ++i) {
    double sw = 0, sx = 0;
    for (int k = 1; k + 1 < m; ++k) {
      const double d = std::abs(value(i, k + 1) - value(i, k - 1));
      sw += d, sx += d * k;
    }
    if (sw > 0) lines.push_back(i), pos.push_back(sx / sw);
  }
  if (lines.size() < 16) return out;
  // Quadratic fit pos = c0 + c1 l + c2 l^2 (l centred), least squares.
  const double lc = 0.5 * (n - 1);
  Eigen::MatrixXd A(lines.size(), 3);
  Eigen::VectorXd b(lines.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    const double l = lines[i] - lc;
    A.row(i) << 1, l, l * l;
    b(i) = pos[i];
  }
  const Eigen::Vector3d c = A.colPivHouseholderQr().solve(b);
  out.edge_offset = c(0);

  // Edge spread function: every pixel by its signed distance from the fitted curve (along the local normal).
  constexpr double kBin = 0.25;
  const int half = static_cast<int>(std::floor(0.5 * m / kBin));
  std::vector<double> sum(2 * half + 1, 0.0), count(2 * half + 1, 0.0);
  double mean_slope = 0;
  for (int i = 0; i < n; ++i) {
    const double l = i - lc, edge = c(0) + c(1) * l + c(2) * l * l, slope = c(1) + 2 * c(2) * l;
    mean_slope += slope / n;
    const double cosine = 1.0 / std::sqrt(1 + slope * slope);
    for (int k = 0; k < m; ++k) {
      const int bin = static_cast<int>(std::lround((k - edge) * cosine / kBin)) + half;
      if (bin < 0 || bin > 2 * half) continue;
      sum[bin] += value(i, k), count[bin] += 1;
    }
  }
  // Bins without pixels take their neighbours' mean (interpolated); the ends are held.
  std::vector<double> esf(sum.size(), NAN);
  for (size_t k = 0; k < esf.size(); ++k)
    if (count[k] > 0) esf[k] = sum[k] / count[k];
  for (size_t k = 0; k < esf.size(); ++k) {
    if (!std::isnan(esf[k])) continue;
    size_t lo = k, hi = k;
    while (lo > 0 && std::isnan(esf[lo])) --lo;
    while (hi + 1 < esf.size() && std::isnan(esf[hi])) ++hi;
    if (std::isnan(esf[lo]) && std::isnan(esf[hi])) return out;
    esf[k] = std::isnan(esf[lo])   ? esf[hi]
             : std::isnan(esf[hi]) ? esf[lo]
                                   : esf[lo] + (esf[hi] - esf[lo]) * double(k - lo) / double(hi - lo);
  }
  // Line spread function: central differences, Hamming-windowed about its centroid.
  const size_t L = esf.size();
  std::vector<double> lsf(L, 0.0);
  for (size_t k = 1; k + 1 < L; ++k) lsf[k] = 0.5 * (esf[k + 1] - esf[k - 1]);
  double s0 = 0, s1 = 0;
  for (size_t k = 0; k < L; ++k) s0 += lsf[k], s1 += lsf[k] * k;
  if (s0 == 0) return out;
  const double centre = s1 / s0, width = double(L - 1);
  for (size_t k = 0; k < L; ++k) {
    const double x = (k - centre) / width;
    lsf[k] *= std::abs(x) <= 1 ? 0.54 + 0.46 * std::cos(2 * M_PI * x) : 0.0;
  }
  double dc = 0;
  for (double v : lsf) dc += v;
  if (dc == 0) return out;
  double prev = 1.0;
  out.mtf50 = 1.0;
  bool crossed = false;
  for (int j = 0; j <= 128; ++j) {
    const double nu = j / 128.0;
    std::complex<double> f = 0;
    for (size_t k = 0; k < L; ++k) f += lsf[k] * std::polar(1.0, -2 * M_PI * nu * (k - centre) * kBin);
    // The central difference over +-1 bin multiplies the spectrum by sinc(2 nu kBin); undone.
    const double x = 2 * M_PI * nu * kBin, derivative = x == 0 ? 1.0 : std::sin(x) / x;
    const double v = std::abs(f) / std::abs(dc) / derivative;
    out.nu.push_back(nu), out.mtf.push_back(v);
    if (!crossed && j > 0 && v <= 0.5) {
      crossed = true;
      out.mtf50 = nu - 1.0 / 128 + (1.0 / 128) * (prev - 0.5) / (prev - v);
    }
    prev = v;
  }
  const double nx = 1.0 / std::sqrt(1 + mean_slope * mean_slope), ny = -mean_slope * nx;
  out.normal = across_x ? Vec2d(nx, ny) : Vec2d(ny, nx);
  out.ok = true;
  return out;
}

}  // namespace hovs::optics
