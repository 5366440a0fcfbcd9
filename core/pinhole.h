// Pinhole camera with optional radial-tangential distortion.
//
//   X = (x, y, z) in the camera frame (x right, y down, z forwards), z > 0
//   m = (x / z, y / z), m_d = Distort(m)            (distortion.h)
//   u = fx * m_d.x + cx,  v = fy * m_d.y + cy      (pixels, centre of the top-left pixel at (0, 0))
//
// Parameters, in order: fx, fy, cx, cy, k1, k2, p1, p2. Valid domain: z > 0 (ImgFromCam returns false
// otherwise); CamFromImg returns a unit bearing with positive z.
#pragma once

#include <array>
#include <cmath>

#include "core/distortion.h"
#include "core/error.h"
#include "core/model_check.h"
#include "core/types.h"

namespace hovs {

template <class T>
struct PinholeCamera {
  static constexpr int kNumParams = 8;

  int width = 0;   // pixels; 0 = unbounded
  int height = 0;  // pixels
  T fx = T(1), fy = T(1), cx = T(0), cy = T(0);
  RadTanDistortion<T> distortion;

  // A camera from physical numbers: focal length and pixel pitch in metres; principal point at the image
  // centre ((W - 1) / 2, (H - 1) / 2) unless given.
  static PinholeCamera FromPhysical(double focal_length, double pixel_pitch, int width, int height) {
    PinholeCamera cam;
    cam.width = width;
    cam.height = height;
    cam.fx = T(focal_length / pixel_pitch);
    cam.fy = cam.fx;
    cam.cx = T(0.5 * (width - 1));
    cam.cy = T(0.5 * (height - 1));
    return cam;
  }

  // Throws hovs::Error naming the bad parameter.
  void Check(const std::string& where = "pinhole camera") const {
    const double vals[] = {ScalarPart(fx), ScalarPart(fy), ScalarPart(cx), ScalarPart(cy)};
    for (double v : vals) HOVS_REQUIRE(std::isfinite(v), where, "parameters must be finite");
    HOVS_REQUIRE(
        ScalarPart(fx) > 0 && ScalarPart(fy) > 0 && ScalarPart(fx) <= kMaxFocalPx && ScalarPart(fy) <= kMaxFocalPx,
        where, "focal lengths must be in (0, ", kMaxFocalPx, "] px (fx = ", ScalarPart(fx), ", fy = ", ScalarPart(fy),
        ")");
    CheckImageAndCentre(width, height, ScalarPart(cx), ScalarPart(cy), where);
    distortion.Check(where);
  }

  bool InImage(const Vec2<T>& uv) const {
    if (width <= 0 || height <= 0) return true;
    const double u = ScalarPart(uv(0)), v = ScalarPart(uv(1));
    return u >= -0.5 && v >= -0.5 && u <= width - 0.5 && v <= height - 0.5;
  }

  bool ImgFromCam(const Vec3<T>& X, Vec2<T>* uv) const {
    if (!(ScalarPart(X(2)) > 0)) return false;
    const Vec2<T> m(X(0) / X(2), X(1) / X(2));
    const Vec2<T> md = distortion.Distort(m);
    *uv = Vec2<T>(fx * md(0) + cx, fy * md(1) + cy);
    return true;
  }

  bool CamFromImg(const Vec2<T>& uv, Vec3<T>* bearing) const {
    Vec2<T> m;
    if (!NormalisedFromImg(uv, &m)) return false;
    *bearing = Normalized(Vec3<T>(m(0), m(1), T(1)));
    return true;
  }

  // The undistorted point (x, y) on the plane z = 1 whose ray images at uv: CamFromImg before normalising.
  bool NormalisedFromImg(const Vec2<T>& uv, Vec2<T>* m) const {
    const Vec2<T> md((uv(0) - cx) / fx, (uv(1) - cy) / fy);
    return distortion.Undistort(md, m);
  }

  // NormalisedFromImg for n points (u[i], v[i]) (the renderer's per-sample path): the same values; without
  // distortion a loop the compiler vectorises. ok[i] = 0 where undistortion fails (x, y set to 0 there).
  void NormalisedFromImgBatch(int n, const T* u, const T* v, T* x, T* y, unsigned char* ok) const {
    if (distortion.IsZero()) {
      const T fx_ = fx, fy_ = fy, cx_ = cx, cy_ = cy;
      for (int i = 0; i < n; ++i) x[i] = (u[i] - cx_) / fx_, y[i] = (v[i] - cy_) / fy_;
      for (int i = 0; i < n; ++i) ok[i] = 1;
      return;
    }
    for (int i = 0; i < n; ++i) {
      Vec2<T> m;
      ok[i] = NormalisedFromImg(Vec2<T>(u[i], v[i]), &m);
      x[i] = ok[i] ? m(0) : T(0), y[i] = ok[i] ? m(1) : T(0);
    }
  }

  std::array<T, kNumParams> Params() const {
    return {fx, fy, cx, cy, distortion.k1, distortion.k2, distortion.p1, distortion.p2};
  }
  static PinholeCamera FromParams(const T* p, int width = 0, int height = 0) {
    PinholeCamera cam;
    cam.width = width;
    cam.height = height;
    cam.fx = p[0], cam.fy = p[1], cam.cx = p[2], cam.cy = p[3];
    cam.distortion = {p[4], p[5], p[6], p[7]};
    return cam;
  }

  template <class U>
  PinholeCamera<U> Cast() const {
    PinholeCamera<U> c;
    c.width = width;
    c.height = height;
    c.fx = ConvertScalar<U>(fx), c.fy = ConvertScalar<U>(fy), c.cx = ConvertScalar<U>(cx), c.cy = ConvertScalar<U>(cy);
    c.distortion = distortion.template Cast<U>();
    return c;
  }
};

}  // namespace hovs
