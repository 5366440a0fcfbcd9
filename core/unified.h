// The unified (Mei) camera model, written in the mirror frame of conventions.h.
//
//   X in the mirror frame, n = |X|,  denom = xi * n - z                       (Mei: z_m + xi * n, z_m = -z)
//   m = (x, y) / denom,  m_d = Distort(m)                                     (distortion.h)
//   u = fx * m_d.x + skew * m_d.y + cx,  v = fy * m_d.y + cy
// Inverse: m from the pixel, r^2 = |m|^2, k = (xi + sqrt(1 + (1 - xi^2) r^2)) / (r^2 + 1),
//   bearing = (k m.x, k m.y, xi - k).
// OpenCV omnidir's frame is (x, y, -z) of this one: same xi, K and distortion.
//
// Parameters, in order: xi, fx, fy, cx, cy, skew, k1, k2, p1, p2.
// Valid domain: z < w * n with w = xi for xi <= 1 and 1 / xi otherwise; back-projection needs
// 1 + (1 - xi^2) r^2 >= 0.
//
// UnifiedFromCatadioptric: a single-viewpoint, axis-aligned hyperboloid rig is exactly a unified camera with
//   xi = 2 a c / (2 a^2 + b^2),  eta = b^2 / (2 a^2 + b^2),
//   fx_u = eta fx, fy_u = eta fy, same centre, k1_u = eta^2 k1, k2_u = eta^4 k2, p1_u = eta p1, p2_u = eta p2.
// (Geyer-Daniilidis / Barreto: xi = d / sqrt(d^2 + 4p^2) with d = 2c, 4p = 2 b^2 / a, the latus rectum.)
#pragma once

#include <cmath>
#include <string>

#include "core/catadioptric.h"
#include "core/distortion.h"
#include "core/error.h"
#include "core/model_check.h"
#include "core/types.h"

namespace hovs {

template <class T>
struct UnifiedModel {
  static constexpr int kNumParams = 10;
  int width = 0, height = 0;
  T xi = T(0), fx = T(1), fy = T(1), cx = T(0), cy = T(0), skew = T(0);
  RadTanDistortion<T> distortion;

  bool ImgFromCam(const Vec3<T>& X, Vec2<T>* uv) const {
    using std::sqrt;
    const T n = sqrt(X.squaredNorm());
    const double xi_d = ScalarPart(xi);
    const double w = xi_d <= 1 ? xi_d : 1.0 / xi_d;
    if (!(ScalarPart(X(2)) < w * ScalarPart(n))) return false;
    const T denom = xi * n - X(2);
    if (!(ScalarPart(denom) > 0)) return false;
    const Vec2<T> md = distortion.Distort(Vec2<T>(X(0) / denom, X(1) / denom));
    *uv = Vec2<T>(fx * md(0) + skew * md(1) + cx, fy * md(1) + cy);
    return true;
  }

  bool CamFromImg(const Vec2<T>& uv, Vec3<T>* bearing) const {
    using std::sqrt;
    const T my_d = (uv(1) - cy) / fy;
    const T mx_d = (uv(0) - cx - skew * my_d) / fx;
    Vec2<T> m;
    if (!distortion.Undistort(Vec2<T>(mx_d, my_d), &m)) return false;
    const T r2 = m.squaredNorm();
    const T disc = T(1) + (T(1) - xi * xi) * r2;
    if (!(ScalarPart(disc) >= 0)) return false;
    const T k = (xi + sqrt(disc)) / (r2 + T(1));
    *bearing = Normalized<T>(Vec3<T>(k * m(0), k * m(1), xi - k));
    return true;
  }

  void Check(const std::string& where = "unified model") const {
    HOVS_REQUIRE(std::isfinite(ScalarPart(xi)) && ScalarPart(xi) >= 0 && ScalarPart(xi) <= 100, where,
                 "xi must be a number in [0, 100] (got ", ScalarPart(xi), ")");
    HOVS_REQUIRE(
        ScalarPart(fx) > 0 && ScalarPart(fy) > 0 && ScalarPart(fx) <= kMaxFocalPx && ScalarPart(fy) <= kMaxFocalPx,
        where, "focal lengths must be in (0, ", kMaxFocalPx, "] px (fx = ", ScalarPart(fx), ", fy = ", ScalarPart(fy),
        ")");
    HOVS_REQUIRE(std::isfinite(ScalarPart(skew)) && std::abs(ScalarPart(skew)) <= kMaxFocalPx, where,
                 "skew must be finite (got ", ScalarPart(skew), ")");
    CheckImageAndCentre(width, height, ScalarPart(cx), ScalarPart(cy), where);
    distortion.Check(where);
  }

  template <class U>
  UnifiedModel<U> Cast() const {
    UnifiedModel<U> m;
    m.width = width, m.height = height;
    m.xi = ConvertScalar<U>(xi), m.fx = ConvertScalar<U>(fx), m.fy = ConvertScalar<U>(fy);
    m.cx = ConvertScalar<U>(cx), m.cy = ConvertScalar<U>(cy), m.skew = ConvertScalar<U>(skew);
    m.distortion = distortion.template Cast<U>();
    return m;
  }
};

// Exact conversion of an ideal rig (pinhole at F2, optical axis on the mirror axis) into the unified model.
// Throws hovs::Error if the rig is not single-viewpoint or not axis-aligned.
template <class T>
UnifiedModel<T> UnifiedFromCatadioptric(const CatadioptricCamera<T>& rig) {
  HOVS_REQUIRE(rig.IsSingleViewpoint(1e-12), "unified model from design",
               "the camera centre is not at the second focus: no single viewpoint, no unified model");
  const auto& q = rig.cam_from_mirror.rotation;
  const double angle =
      2 * std::atan2(std::sqrt(ScalarPart(q.x()) * ScalarPart(q.x()) + ScalarPart(q.y()) * ScalarPart(q.y()) +
                               ScalarPart(q.z()) * ScalarPart(q.z())),
                     std::abs(ScalarPart(q.w())));
  HOVS_REQUIRE(angle < 1e-12, "unified model from design", "the camera is rotated relative to the mirror axis (", angle,
               " rad)");
  const T a = rig.mirror.a, b = rig.mirror.b, c = rig.mirror.c();
  const T den = T(2) * a * a + b * b;
  const T eta = b * b / den;
  UnifiedModel<T> m;
  m.width = rig.camera.width, m.height = rig.camera.height;
  m.xi = T(2) * a * c / den;
  m.fx = eta * rig.camera.fx, m.fy = eta * rig.camera.fy;
  m.cx = rig.camera.cx, m.cy = rig.camera.cy;
  m.skew = T(0);
  const auto& k = rig.camera.distortion;
  m.distortion = {eta * eta * k.k1, eta * eta * eta * eta * k.k2, eta * k.p1, eta * k.p2};
  return m;
}

}  // namespace hovs
