// Small vector aliases and scalar helpers shared by the templated models.
#pragma once

#include <ceres/jet.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <type_traits>

namespace hovs {

template <class T>
using Vec2 = Eigen::Matrix<T, 2, 1>;
template <class T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using Mat2 = Eigen::Matrix<T, 2, 2>;
template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3>;

using Vec2d = Vec2<double>;
using Vec3d = Vec3<double>;

template <class T>
struct IsJet : std::false_type {};
template <class T, int N>
struct IsJet<ceres::Jet<T, N>> : std::true_type {};

// The value part of a scalar: the scalar itself for double, .a for a ceres::Jet.
inline double ScalarPart(double v) { return v; }
template <class T, int N>
double ScalarPart(const ceres::Jet<T, N>& v) {
  return ScalarPart(v.a);
}

// Converts between scalar types: double -> Jet (zero derivative), Jet -> double (value), same -> same.
template <class U, class T>
U ConvertScalar(const T& v) {
  if constexpr (std::is_same_v<U, T>) {
    return v;
  } else if constexpr (std::is_same_v<U, double>) {
    return ScalarPart(v);
  } else {
    return U(ScalarPart(v));
  }
}

template <class U, class T, int R, int C>
Eigen::Matrix<U, R, C> ConvertMatrix(const Eigen::Matrix<T, R, C>& m) {
  Eigen::Matrix<U, R, C> out;
  for (int i = 0; i < m.size(); ++i) out(i) = ConvertScalar<U>(m(i));
  return out;
}

// Unit vector; the norm of a Jet vector is differentiated correctly.
template <class T>
Vec3<T> Normalized(const Vec3<T>& v) {
  using std::sqrt;
  const T n = sqrt(v.squaredNorm());
  return v / n;
}

}  // namespace hovs
