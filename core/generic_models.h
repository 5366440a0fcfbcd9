// Generic wide-angle camera models that other tools use (Usenko et al. 2018; Kannala and Brandt 2006), so that a
// hovs calibration can be refitted to them (calib/model_refit.h) and handed to Basalt, Kalibr or OpenVINS:
//
//   double sphere (DS):  d1 = |X|, d2 = |(x, y, xi d1 + z)|,  m = (x, y) / (alpha d2 + (1 - alpha)(xi d1 + z))
//   extended unified (EUCM):  d = sqrt(beta (x^2 + y^2) + z^2),  m = (x, y) / (alpha d + (1 - alpha) z)
//   Kannala-Brandt (KB4, OpenCV fisheye, Kalibr "equidistant"):  theta = atan2(|(x, y)|, z),
//        r(theta) = theta + k1 theta^3 + k2 theta^5 + k3 theta^7 + k4 theta^9,  m = r(theta) (x, y) / |(x, y)|
//   pixel = (fx m.x + cx, fy m.y + cy)
//
// Frame: these tools' camera frame, z along the optical axis. For a catadioptric unit that is (x, y, -z) of hovs'
// mirror frame (OmniFromMirror), as for OpenCV omnidir (core/unified.h): the same intrinsics then reproduce the
// image. Parameters in the order the tools list them: DS xi, alpha, fx, fy, cx, cy; EUCM alpha, beta, fx, fy, cx,
// cy; KB fx, fy, cx, cy, k1, k2, k3, k4. ImgFromCam fails outside each model's valid domain (DS and EUCM: the
// conditions of the paper; KB: theta beyond where r(theta) stops increasing).
#pragma once

#include <array>
#include <cmath>
#include <string>

#include "core/types.h"

namespace hovs {

template <class T>
Vec3<T> OmniFromMirror(const Vec3<T>& m) {
  return Vec3<T>(m(0), m(1), -m(2));
}

// The kinds by name: "ds", "eucm", "kb".
enum class GenericKind { kDoubleSphere, kEucm, kKannalaBrandt };

template <class T>
struct GenericModel {
  GenericKind kind = GenericKind::kDoubleSphere;
  int width = 0, height = 0;
  // DS: xi, alpha, fx, fy, cx, cy; EUCM: alpha, beta, fx, fy, cx, cy; KB: fx, fy, cx, cy, k1, k2, k3, k4.
  std::array<T, 8> p{};
  double theta_max = M_PI;  // KB: the largest angle from the axis where r(theta) still increases

  static int Size(GenericKind k) { return k == GenericKind::kKannalaBrandt ? 8 : 6; }
  int Size() const { return Size(kind); }

  // Pixel of a point in the tools' frame (z along the optical axis).
  bool ImgFromCam(const Vec3<T>& X, Vec2<T>* uv) const {
    using std::sqrt;
    const T x = X(0), y = X(1), z = X(2);
    switch (kind) {
      case GenericKind::kDoubleSphere: {
        const T xi = p[0], alpha = p[1];
        const T d1 = sqrt(x * x + y * y + z * z);
        const T k = xi * d1 + z;
        const T d2 = sqrt(x * x + y * y + k * k);
        const double a = ScalarPart(alpha), xd = ScalarPart(xi);
        const double w1 = a <= 0.5 ? a / (1 - a) : (1 - a) / a;
        const double w2 = (w1 + xd) / std::sqrt(2 * w1 * xd + xd * xd + 1);
        if (!(ScalarPart(z) > -w2 * ScalarPart(d1))) return false;
        const T den = alpha * d2 + (T(1) - alpha) * k;
        if (!(ScalarPart(den) > 0)) return false;
        *uv = Vec2<T>(p[2] * x / den + p[4], p[3] * y / den + p[5]);
        return true;
      }
      case GenericKind::kEucm: {
        const T alpha = p[0], beta = p[1];
        const T d = sqrt(beta * (x * x + y * y) + z * z);
        const double a = ScalarPart(alpha);
        const double w = a <= 0.5 ? a / (1 - a) : (1 - a) / a;
        // Valid where z > -w d (with alpha > 0.5 the projection is one-to-one only there).
        if (!(ScalarPart(z) > -w * ScalarPart(d))) return false;
        const T den = alpha * d + (T(1) - alpha) * z;
        if (!(ScalarPart(den) > 0)) return false;
        *uv = Vec2<T>(p[2] * x / den + p[4], p[3] * y / den + p[5]);
        return true;
      }
      case GenericKind::kKannalaBrandt: {
        using std::atan2;
        const T r2 = x * x + y * y;
        if (!(ScalarPart(r2) > 0)) {
          if (!(ScalarPart(z) > 0)) return false;
          *uv = Vec2<T>(p[2], p[3]);
          return true;
        }
        const T r = sqrt(r2), th = atan2(r, z);
        if (!(ScalarPart(th) <= theta_max)) return false;
        const T t2 = th * th;
        const T rt = th * (T(1) + t2 * (p[4] + t2 * (p[5] + t2 * (p[6] + t2 * p[7]))));
        *uv = Vec2<T>(p[0] * rt * x / r + p[2], p[1] * rt * y / r + p[3]);
        return true;
      }
    }
    return false;
  }

  // The angle from the axis where KB's r(theta) stops increasing (up to pi): its domain.
  void SetKannalaBrandtDomain() {
    theta_max = M_PI;
    double prev = 0;
    for (int i = 1; i <= 3600; ++i) {
      const double th = M_PI * i / 3600, t2 = th * th;
      const double r =
          th *
          (1 + t2 * (ScalarPart(p[4]) + t2 * (ScalarPart(p[5]) + t2 * (ScalarPart(p[6]) + t2 * ScalarPart(p[7])))));
      if (!(r > prev)) {
        theta_max = M_PI * (i - 1) / 3600;
        return;
      }
      prev = r;
    }
  }
};

inline const char* GenericKindName(GenericKind k) {
  return k == GenericKind::kDoubleSphere ? "ds" : k == GenericKind::kEucm ? "eucm" : "kb";
}

}  // namespace hovs
