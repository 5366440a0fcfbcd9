// Small statistics shared by the evaluation code of every layer: angles between bearings, the best rotation
// between two bundles of bearings, running mean/max/RMS, and a median.
#pragma once

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/types.h"

namespace hovs {

// The angle between two directions, degrees; atan2 of |a x b| and a.b is exact near 0 and 180 degrees, where
// acos of the dot product loses half the digits. Neither needs unit length.
inline double AngleBetweenDeg(const Vec3d& a, const Vec3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

// The rotation R minimising sum |a_i - R b_i|^2 over pairs (a_i, b_i) of unit bearings (Kabsch: the SVD of
// sum b a^T, with the sign that keeps R proper). Identity for fewer than two pairs.
inline Mat3<double> BestRotation(const std::vector<std::pair<Vec3d, Vec3d>>& a_b) {
  if (a_b.size() < 2) return Mat3<double>::Identity();
  Mat3<double> H = Mat3<double>::Zero();
  for (const auto& [a, b] : a_b) H += b * a.transpose();
  const Eigen::JacobiSVD<Mat3<double>> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3<double> D = Mat3<double>::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() > 0 ? 1 : -1;
  return svd.matrixV() * D * svd.matrixU().transpose();
}

// Mean, maximum and RMS of a stream of values (errors, distances); empty until the first Add.
struct RunningStats {
  double sum = 0, sum_sq = 0, max = 0;
  long count = 0;

  void Add(double v) {
    sum += v, sum_sq += v * v, max = count ? std::max(max, v) : v;
    ++count;
  }
  bool empty() const { return count == 0; }
  double Mean() const { return count ? sum / count : 0.0; }
  double Rms() const { return count ? std::sqrt(sum_sq / count) : 0.0; }
};

// The median of the values (the upper one of an even count, as nth_element gives); 0 for none.
inline double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The p-quantile (p in [0, 1]) of sorted values by the nearest rank: the smallest value with at least a share p of
// the values at or below it (index ceil(p n) - 1). 0 for none.
inline double Percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  const double rank = std::ceil(p * static_cast<double>(sorted.size()));
  const size_t k = static_cast<size_t>(std::max(1.0, rank)) - 1;
  return sorted[std::min(k, sorted.size() - 1)];
}

// Order statistics of a sample (latencies, errors): median (upper of an even count), 95th percentile (the value
// at index floor(0.95 n) of the sorted sample), maximum and mean. All 0 for an empty sample.
struct SampleSummary {
  size_t count = 0;
  double median = 0, p95 = 0, max = 0, mean = 0;
};

inline SampleSummary Summarise(std::vector<double> v) {
  SampleSummary s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  s.count = v.size();
  s.median = v[v.size() / 2], s.p95 = v[std::min(v.size() - 1, v.size() * 95 / 100)], s.max = v.back();
  s.mean = sum / v.size();
  return s;
}

}  // namespace hovs
