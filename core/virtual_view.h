// Virtual views seen from a catadioptric unit's viewpoint F1: a pinhole (perspective) camera, a cylindrical
// panorama and a longitude-latitude (equirectangular) panorama. Bearings are in the mirror frame of
// conventions.h (z along the mirror axis, from the camera towards the mirror: "up" for an upright unit).
//
// View frame
//   A view has a rotation mirror_from_view. For a perspective view the view frame is a camera frame (x right,
//   y down, z forward). It is built from yaw, pitch and roll (radians):
//     forward = (cos pitch cos yaw, cos pitch sin yaw, sin pitch)  in the mirror frame,
//     image "down" is the mirror's -z projected on the image plane, roll turns the camera about forward
//     (right-handed: positive roll turns the camera's x axis towards its y axis).
//   Yaw is the azimuth measured in the mirror frame from +x towards +y; pitch is the elevation (negative: below
//   the horizontal plane through F1).
//   For a panorama the view frame is a "pole" frame: azimuth = atan2(y, x), elevation = asin(z) in view
//   coordinates. With the identity rotation the pole is the mirror axis; depth rectification turns the pole
//   onto the baseline so that epipolar curves become rows.
//
// Pixels (conventions.h: pixel centres at integers, the image spans [-0.5, W - 0.5] x [-0.5, H - 0.5])
//   Panorama column u: azimuth = azimuth_centre + azimuth_span * (0.5 - (u + 0.5) / W)
//     (azimuth decreases to the right, so that the panorama reads like a view from inside, not mirrored).
//   Row v, cylindrical: tan(elevation) = tan(e_max) - (v + 0.5) / H * (tan(e_max) - tan(e_min))
//     (a cylinder around the pole: vertical lines stay vertical and are not stretched).
//   Row v, longlat: elevation = e_max - (v + 0.5) / H * (e_max - e_min).
//
// Epipolar (stereo rectification; the pole is the baseline, the view frame's +x axis):
//   column u: theta, the angle between the ray and the pole, theta = t_max - (u + 0.5) / W * (t_max - t_min)
//             (stored in azimuth_centre +- azimuth_span / 2: t_min = centre - span / 2, t_max = centre + span / 2);
//   row v:    phi, the angle of the ray's plane around the pole, phi = p_max - (v + 0.5) / H * (p_max - p_min)
//             (stored in elevation_min / elevation_max);
//   bearing (view frame) = (cos theta, sin theta cos phi, sin theta sin phi).
//   Every plane containing the pole is one row: for two units whose views share the pole (the baseline) and
//   the orientation, epipolar curves are rows, and a point's two columns give its two angles to the baseline.
//
// Valid domains: perspective bearings with positive z in the view frame; cylindrical elevations strictly
// inside (-90, 90) degrees; longlat elevations in [-90, 90]. Every function returns false outside.
#pragma once

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/pinhole.h"
#include "core/types.h"

namespace hovs {

enum class ViewProjection { kPerspective, kCylindrical, kLongLat, kEpipolar };

inline const char* ToString(ViewProjection p) {
  switch (p) {
    case ViewProjection::kPerspective: return "perspective";
    case ViewProjection::kCylindrical: return "cylindrical";
    case ViewProjection::kLongLat: return "longlat";
    case ViewProjection::kEpipolar: return "epipolar";
  }
  return "?";
}

// The rotation mirror_from_view of a perspective camera looking along (yaw, pitch), rolled about its axis.
template <class T>
Eigen::Quaternion<T> MirrorFromPerspective(const T& yaw, const T& pitch, const T& roll) {
  using std::cos;
  using std::sin;
  // Base: camera z -> mirror +x, camera x -> mirror -y, camera y -> mirror -z (looking along +x, upright).
  Mat3<T> base;
  base << T(0), T(0), T(1), T(-1), T(0), T(0), T(0), T(-1), T(0);
  const Eigen::AngleAxis<T> r_yaw(yaw, Vec3<T>::UnitZ());
  const Eigen::AngleAxis<T> r_pitch(-pitch, Vec3<T>::UnitY());
  const Eigen::AngleAxis<T> r_roll(roll, Vec3<T>::UnitZ());
  const Mat3<T> R = r_yaw.toRotationMatrix() * r_pitch.toRotationMatrix() * base * r_roll.toRotationMatrix();
  return Eigen::Quaternion<T>(R);
}

template <class T>
struct VirtualView {
  ViewProjection projection = ViewProjection::kPerspective;
  int width = 0, height = 0;
  Eigen::Quaternion<T> mirror_from_view = Eigen::Quaternion<T>::Identity();
  PinholeCamera<T> camera;                              // perspective only (no distortion)
  T azimuth_centre = T(0), azimuth_span = T(2 * M_PI);  // panoramas (radians)
  T elevation_min = T(-M_PI / 4), elevation_max = T(M_PI / 4);

  // A perspective view with horizontal field of view hfov (radians), principal point at the image centre.
  static VirtualView Perspective(int w, int h, const T& hfov, const T& yaw, const T& pitch, const T& roll) {
    using std::tan;
    VirtualView v;
    v.projection = ViewProjection::kPerspective;
    v.width = w, v.height = h;
    v.camera.width = w, v.camera.height = h;
    v.camera.fx = v.camera.fy = T(0.5 * w) / tan(hfov * T(0.5));
    v.camera.cx = T(0.5 * (w - 1));
    v.camera.cy = T(0.5 * (h - 1));
    v.mirror_from_view = MirrorFromPerspective<T>(yaw, pitch, roll);
    return v;
  }
  static VirtualView Panorama(ViewProjection p, int w, int h, const T& e_min, const T& e_max, const T& az_centre = T(0),
                              const T& az_span = T(2 * M_PI)) {
    VirtualView v;
    v.projection = p;
    v.width = w, v.height = h;
    v.elevation_min = e_min, v.elevation_max = e_max;
    v.azimuth_centre = az_centre, v.azimuth_span = az_span;
    return v;
  }

  // Unit bearing (mirror frame) of view pixel uv.
  bool MirrorFromImg(const Vec2<T>& uv, Vec3<T>* bearing) const {
    using std::atan;
    using std::cos;
    using std::sin;
    using std::tan;
    Vec3<T> b;
    if (projection == ViewProjection::kPerspective) {
      if (!camera.CamFromImg(uv, &b)) return false;
    } else if (projection == ViewProjection::kEpipolar) {
      const T theta = azimuth_centre + azimuth_span * (T(0.5) - (uv(0) + T(0.5)) / T(width));
      const T phi = elevation_max - (uv(1) + T(0.5)) / T(height) * (elevation_max - elevation_min);
      b = Vec3<T>(cos(theta), sin(theta) * cos(phi), sin(theta) * sin(phi));
    } else {
      const T az = azimuth_centre + azimuth_span * (T(0.5) - (uv(0) + T(0.5)) / T(width));
      const T s = (uv(1) + T(0.5)) / T(height);
      T el;
      if (projection == ViewProjection::kCylindrical) {
        el = atan(tan(elevation_max) - s * (tan(elevation_max) - tan(elevation_min)));
      } else {
        el = elevation_max - s * (elevation_max - elevation_min);
      }
      b = Vec3<T>(cos(el) * cos(az), cos(el) * sin(az), sin(el));
    }
    *bearing = mirror_from_view * b;
    return true;
  }

  // View pixel of a bearing (any length) given in the mirror frame. Panorama columns are returned in
  // [-0.5, W - 0.5) after wrapping the azimuth into the view's span (false outside a partial span).
  bool ImgFromMirror(const Vec3<T>& X, Vec2<T>* uv) const {
    using std::atan2;
    using std::sqrt;
    using std::tan;
    const Vec3<T> b = mirror_from_view.conjugate() * X;
    if (projection == ViewProjection::kPerspective) return camera.ImgFromCam(b, uv);
    if (projection == ViewProjection::kEpipolar) {
      const T theta = atan2(sqrt(b(1) * b(1) + b(2) * b(2)), b(0));
      const T phi = atan2(b(2), b(1));
      *uv = Vec2<T>((T(0.5) - (theta - azimuth_centre) / azimuth_span) * T(width) - T(0.5),
                    (elevation_max - phi) / (elevation_max - elevation_min) * T(height) - T(0.5));
      return true;
    }
    const T rxy = sqrt(b(0) * b(0) + b(1) * b(1));
    const T el = atan2(b(2), rxy);
    T az = atan2(b(1), b(0)) - azimuth_centre;
    // s_u = (u + 0.5) / W = 0.5 - az / span, wrapped into [0, 1).
    T su = T(0.5) - az / azimuth_span;
    const double period = 2 * M_PI / std::abs(ScalarPart(azimuth_span));
    su = su - T(period * std::floor(ScalarPart(su) / period));
    if (!(ScalarPart(su) >= 0 && ScalarPart(su) < 1)) return false;
    T sv;
    if (projection == ViewProjection::kCylindrical) {
      if (!(ScalarPart(rxy) > 0)) return false;
      sv = (tan(elevation_max) - b(2) / rxy) / (tan(elevation_max) - tan(elevation_min));
    } else {
      sv = (elevation_max - el) / (elevation_max - elevation_min);
    }
    *uv = Vec2<T>(su * T(width) - T(0.5), sv * T(height) - T(0.5));
    return true;
  }

  void Check(const std::string& where) const {
    HOVS_REQUIRE(width > 0 && height > 0 && width <= 32768 && height <= 32768, where,
                 "view size must be 1..32768 pixels (got ", width, " x ", height, ")");
    if (projection == ViewProjection::kPerspective) {
      camera.Check(where);
      const double hfov = 2 * std::atan(0.5 * width / ScalarPart(camera.fx));
      HOVS_REQUIRE(hfov < M_PI, where, "a perspective view needs a field of view below 180 degrees");
    } else if (projection == ViewProjection::kEpipolar) {
      const double t0 = ScalarPart(azimuth_centre - azimuth_span * T(0.5));
      const double t1 = ScalarPart(azimuth_centre + azimuth_span * T(0.5));
      HOVS_REQUIRE(t0 >= 0 && t1 <= M_PI + 1e-12 && t0 < t1, where,
                   "epipolar view: angles from the baseline must lie in [0, 180] degrees");
      HOVS_REQUIRE(ScalarPart(elevation_min) < ScalarPart(elevation_max), where,
                   "epipolar view: phi_min must be below phi_max");
    } else {
      const double lo = ScalarPart(elevation_min), hi = ScalarPart(elevation_max);
      const double limit = projection == ViewProjection::kCylindrical ? M_PI / 2 - 1e-6 : M_PI / 2 + 1e-12;
      HOVS_REQUIRE(std::isfinite(lo) && std::isfinite(hi) && lo < hi, where,
                   "elevation_min must be below elevation_max");
      HOVS_REQUIRE(lo > -limit && hi < limit, where, "elevations must lie inside (-90, 90) degrees for a ",
                   ToString(projection), " panorama");
      const double span = std::abs(ScalarPart(azimuth_span));
      HOVS_REQUIRE(span > 0 && span <= 2 * M_PI + 1e-12, where, "azimuth span must be in (0, 360] degrees");
    }
  }
};

}  // namespace hovs
