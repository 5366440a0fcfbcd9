// Rigid transforms named target_from_source (see conventions.h).
#pragma once

#include "core/types.h"

namespace hovs {

template <class T>
struct Rigid3 {
  Eigen::Quaternion<T> rotation = Eigen::Quaternion<T>::Identity();
  Vec3<T> translation = Vec3<T>::Zero();

  Rigid3() = default;
  Rigid3(const Eigen::Quaternion<T>& q, const Vec3<T>& t) : rotation(q), translation(t) {}

  static Rigid3 Identity() { return Rigid3(); }
  static Rigid3 Translation(const Vec3<T>& t) { return Rigid3(Eigen::Quaternion<T>::Identity(), t); }

  // p_target = target_from_source * p_source
  Vec3<T> operator*(const Vec3<T>& p) const { return rotation * p + translation; }
  // target_from_mid * mid_from_source
  Rigid3 operator*(const Rigid3& other) const {
    return Rigid3(rotation * other.rotation, rotation * other.translation + translation);
  }
  Rigid3 Inverse() const {
    const Eigen::Quaternion<T> inv = rotation.conjugate();
    return Rigid3(inv, -(inv * translation));
  }
  Vec3<T> Rotate(const Vec3<T>& v) const { return rotation * v; }

  template <class U>
  Rigid3<U> Cast() const {
    Eigen::Quaternion<U> q(ConvertScalar<U>(rotation.w()), ConvertScalar<U>(rotation.x()),
                           ConvertScalar<U>(rotation.y()), ConvertScalar<U>(rotation.z()));
    return Rigid3<U>(q, ConvertMatrix<U>(translation));
  }
};

using Rigid3d = Rigid3<double>;

// Rotation from an axis-angle vector (radians), e.g. a small tilt (rx, ry, 0).
template <class T>
Eigen::Quaternion<T> QuaternionFromAngleAxis(const Vec3<T>& aa) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta2 = aa.squaredNorm();
  if (ScalarPart(theta2) < 1e-24) {
    return Eigen::Quaternion<T>(T(1), aa.x() * T(0.5), aa.y() * T(0.5), aa.z() * T(0.5)).normalized();
  }
  const T theta = sqrt(theta2);
  const T k = sin(theta * T(0.5)) / theta;
  return Eigen::Quaternion<T>(cos(theta * T(0.5)), aa.x() * k, aa.y() * k, aa.z() * k);
}

}  // namespace hovs
