// The exact catadioptric camera: a hyperboloid mirror (hyperboloid.h) seen by a pinhole camera (pinhole.h)
// placed by cam_from_mirror. This is the physical model the renderer traces and the design study measures.
//
// Single viewpoint (camera centre at F2, any orientation): closed form
//   s = X / |X|,  M = b^2 / (a - c s_z) * s,  uv = camera.ImgFromCam(cam_from_mirror * M)
// General rig (camera off the focus, tilted or offset against the mirror: a physical misalignment): the mirror point M
// obeys the law of reflection between the world point X and the camera centre C. With M = (x, y, z(x, y))
// and tangents T_x = (1, 0, z_x), T_y = (0, 1, z_y), the two equations
//   h . T_x = 0,  h . T_y = 0,   h = (X - M) / |X - M| + (C - M) / |C - M|
// say that h is along the normal (incidence equals reflection, in the plane of the normal). They are solved by
// damped Newton from the single-viewpoint guess and verified afterwards; failure is reported, never guessed.
//
// Back-projection: the pixel's ray from C hits the sheet at M (within the rim) and reflects; the reflected ray
// (origin M, unit direction) is the pixel's view ray. For a single-viewpoint rig it passes through F1, and
// its direction is the unit bearing from the viewpoint.
//
// The camera body is an occluding disc of radius occluder_radius around C, perpendicular to the optical axis
// (by default the lens aperture): it hides the centre of the image, as the camera's own reflection does.
#pragma once

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/hyperboloid.h"
#include "core/newton.h"
#include "core/pinhole.h"
#include "core/rigid.h"
#include "core/types.h"

namespace hovs {

enum class ProjectionStatus {
  kOk = 0,
  kMissesMirror,  // the direction from the viewpoint misses the sheet, or meets it outside the rim
  kInsideMirror,  // the point lies behind the mirror surface (between F1 and the sheet)
  kOccluded,      // the reflected path is blocked by the camera body
  kBehindCamera,  // the mirror point is behind the camera's image plane
  kOutsideImage,  // the pixel falls outside the sensor
  kNoSolution,    // the law-of-reflection solve found no valid mirror point
};

inline const char* ToString(ProjectionStatus s) {
  switch (s) {
    case ProjectionStatus::kOk: return "ok";
    case ProjectionStatus::kMissesMirror: return "misses the mirror";
    case ProjectionStatus::kInsideMirror: return "behind the mirror surface";
    case ProjectionStatus::kOccluded: return "occluded by the camera";
    case ProjectionStatus::kBehindCamera: return "behind the camera";
    case ProjectionStatus::kOutsideImage: return "outside the image";
    case ProjectionStatus::kNoSolution: return "no law-of-reflection solution";
  }
  return "unknown";
}

// Residual of the law of reflection at sheet coordinates xy, for world point X and camera centre C (mirror
// frame). Zero exactly when the reflection law holds at M = mirror.SurfacePoint(xy).
template <class S, class P>
Vec2<S> ReflectionResidual(const HyperboloidMirror<P>& mirror_p, const Vec3<P>& X_p, const Vec3<P>& C_p,
                           const Vec2<S>& xy) {
  const HyperboloidMirror<S> mirror{S(mirror_p.a), S(mirror_p.b), S(mirror_p.rim_diameter)};
  const Vec3<S> X(S(X_p(0)), S(X_p(1)), S(X_p(2)));
  const Vec3<S> C(S(C_p(0)), S(C_p(1)), S(C_p(2)));
  const Vec3<S> M = mirror.SurfacePoint(xy(0), xy(1));
  const Vec3<S> h = Normalized<S>(X - M) + Normalized<S>(C - M);
  const Vec2<S> slope = mirror.Slope(xy(0), xy(1));
  return Vec2<S>(h(0) + h(2) * slope(0), h(1) + h(2) * slope(1));
}

// The camera placement of a misaligned rig: the pinhole at F2 + offset (mirror frame), the camera turned by
// `tilt` (axis-angle, radians) about its own centre, starting from the ideal orientation (optical axis along
// +z). Returns cam_from_mirror. (A physical misalignment; not the article's R_eps, t_eps, which are OCamCalib's
// affine terms and image centre: PolynomialModel's c, d, e and cx, cy.)
template <class T>
Rigid3<T> CamFromMirrorMisaligned(const HyperboloidMirror<T>& mirror, const Vec3<T>& tilt, const Vec3<T>& offset) {
  const Rigid3<T> mirror_from_cam(QuaternionFromAngleAxis<T>(tilt), Vec3<T>(mirror.SecondFocus() + offset));
  return mirror_from_cam.Inverse();
}

template <class T>
struct CatadioptricCamera {
  HyperboloidMirror<T> mirror;
  PinholeCamera<T> camera;
  Rigid3<T> cam_from_mirror;  // aligned: identity rotation, translation (0, 0, 2c)
  T occluder_radius = T(0);   // camera body / lens disc radius around the pinhole

  // The ideal rig: pinhole at F2, optical axis along the mirror axis.
  static CatadioptricCamera Aligned(const HyperboloidMirror<T>& mirror, const PinholeCamera<T>& camera,
                                    const T& occluder_radius) {
    CatadioptricCamera rig;
    rig.mirror = mirror;
    rig.camera = camera;
    rig.cam_from_mirror = Rigid3<T>::Translation(Vec3<T>(T(0), T(0), T(2) * mirror.c()));
    rig.occluder_radius = occluder_radius;
    return rig;
  }

  // Camera centre and optical axis in the mirror frame.
  Vec3<T> CameraCentre() const { return cam_from_mirror.Inverse().translation; }
  Vec3<T> OpticalAxis() const { return cam_from_mirror.rotation.conjugate() * Vec3<T>(T(0), T(0), T(1)); }

  // True when the camera centre is at F2 (within tolerance metres): the closed form applies.
  bool IsSingleViewpoint(double tolerance = 1e-12) const {
    const Vec3d d = ConvertMatrix<double>(Vec3<T>(CameraCentre() - mirror.SecondFocus()));
    return d.norm() <= tolerance * (1.0 + ScalarPart(mirror.c()));
  }

  // Projection of a point X given in the mirror frame. Uses the closed form for a single-viewpoint rig and
  // the law-of-reflection solve otherwise. mirror_point (optional) receives M.
  ProjectionStatus ImgFromMirror(const Vec3<T>& X, Vec2<T>* uv, Vec3<T>* mirror_point = nullptr) const {
    return IsSingleViewpoint() ? ImgFromMirrorSvp(X, uv, mirror_point) : ImgFromMirrorGeneral(X, uv, mirror_point);
  }

  // Closed form; only meaningful when IsSingleViewpoint().
  ProjectionStatus ImgFromMirrorSvp(const Vec3<T>& X, Vec2<T>* uv, Vec3<T>* mirror_point = nullptr) const {
    Vec3<T> M;
    if (!mirror.PointAlong(X, &M)) return ProjectionStatus::kMissesMirror;
    if (!mirror.WithinRim(M)) return ProjectionStatus::kMissesMirror;
    if (!(ScalarPart(X.squaredNorm()) > ScalarPart(M.squaredNorm()))) return ProjectionStatus::kInsideMirror;
    return Finish(X, M, uv, mirror_point);
  }

  // Law-of-reflection solve; valid for every rig (equals the closed form on a single-viewpoint rig).
  ProjectionStatus ImgFromMirrorGeneral(const Vec3<T>& X, Vec2<T>* uv, Vec3<T>* mirror_point = nullptr) const {
    Vec3<T> M;
    const ProjectionStatus s = SolveReflectionPoint(X, &M);
    if (s != ProjectionStatus::kOk) return s;
    return Finish(X, M, uv, mirror_point);
  }

  // The mirror point where X reflects into the camera centre. Solved in double, lifted to T.
  ProjectionStatus SolveReflectionPoint(const Vec3<T>& X, Vec3<T>* M) const {
    return SolveReflectionPointVia(X, CameraCentre(), M);
  }

  // The mirror point where X reflects into the point C (mirror frame: the camera centre, or a point of a thin
  // lens's pupil), tried from `start` (sheet x, y; e.g. the solution for a nearby C) before the usual guesses.
  ProjectionStatus SolveReflectionPointVia(const Vec3<T>& X, const Vec3<T>& C, Vec3<T>* M,
                                           const Vec2d* start = nullptr) const {
    const HyperboloidMirror<double> md = mirror.template Cast<double>();
    const Vec3d Xd = ConvertMatrix<double>(X);
    const Vec3d Cd = ConvertMatrix<double>(C);
    const double rim = md.RimRadius();
    const auto residual = [&](const auto& xy) { return ReflectionResidual(md, Xd, Cd, xy); };

    // Starting points: the caller's, the single-viewpoint guess, then points along the azimuth of X.
    Vec2d starts[5];
    int num_starts = 0;
    if (start) starts[num_starts++] = *start;
    Vec3d m0;
    if (md.PointAlong(Xd, &m0)) starts[num_starts++] = m0.head<2>();
    const double rxy = Xd.head<2>().norm();
    const Vec2d dir = rxy > 0 ? Vec2d(Xd.head<2>() / rxy) : Vec2d(1, 0);
    for (double f : {0.5, 0.9, 0.1}) starts[num_starts++] = f * rim * dir;

    NewtonOptions options;
    options.max_step = 0.25 * rim;
    options.max_iterations = 60;
    options.residual_tolerance = 1e-15;
    for (int i = 0; i < num_starts; ++i) {
      Vec2d xy = starts[i];
      const NewtonResult r = SolveNewton2(residual, &xy, options);
      if (!r.converged || r.residual_norm > 1e-12) continue;
      const Vec3d Md = md.SurfacePoint(xy(0), xy(1));
      if (!md.WithinRim(Md)) return ProjectionStatus::kMissesMirror;
      const Vec3d n = md.Normal(Md);
      if (!((Xd - Md).dot(n) > 0)) return ProjectionStatus::kInsideMirror;
      if (!((Cd - Md).dot(n) > 0)) return ProjectionStatus::kNoSolution;
      const auto residual_t = [&](const Vec2<T>& p) { return ReflectionResidual(mirror, X, C, p); };
      const Vec2<T> xy_t = LiftNewton2<T>(residual_t, xy, r.jacobian);
      *M = mirror.SurfacePoint(xy_t(0), xy_t(1));
      return ProjectionStatus::kOk;
    }
    return ProjectionStatus::kNoSolution;
  }

  // The view ray of pixel uv after the mirror: origin on the sheet, unit direction. False when the pixel's
  // ray misses the mirror (outside the rim image) or the pixel cannot be back-projected.
  bool RayFromImg(const Vec2<T>& uv, Vec3<T>* mirror_point, Vec3<T>* direction) const {
    Vec3<T> bearing_cam;
    if (!camera.CamFromImg(uv, &bearing_cam)) return false;
    return ReflectCameraRay(CameraCentre(), cam_from_mirror.rotation.conjugate() * bearing_cam, mirror_point,
                            direction);
  }

  // Reflection of a ray leaving the camera side (origin o, direction v, mirror frame; e.g. from a point of a
  // thin lens): the mirror point within the rim and the unit reflected direction. False if it misses.
  bool ReflectCameraRay(const Vec3<T>& o, const Vec3<T>& v, Vec3<T>* mirror_point, Vec3<T>* direction) const {
    T t;
    if (!mirror.IntersectSheet(o, v, &t)) return false;
    const Vec3<T> M = o + t * v;
    if (!mirror.WithinRim(M)) return false;
    const Vec3<T> n = mirror.Normal(M);
    *mirror_point = M;
    *direction = Normalized<T>(v - T(2) * v.dot(n) * n);
    return true;
  }

  // Unit bearing of pixel uv as seen from the viewpoint F1 (the reflected direction). For a rig that is not
  // single-viewpoint, this is the direction only; use RayFromImg for the origin.
  bool CamFromImg(const Vec2<T>& uv, Vec3<T>* bearing) const {
    Vec3<T> M;
    return RayFromImg(uv, &M, bearing);
  }

  // Does the reflected ray from M along direction hit the camera body?
  bool RayHitsCamera(const Vec3<T>& M, const Vec3<T>& direction, double max_t = HUGE_VAL) const {
    const Vec3d Md = ConvertMatrix<double>(M), d = ConvertMatrix<double>(direction);
    const Vec3d C = ConvertMatrix<double>(Vec3<T>(CameraCentre()));
    const Vec3d axis = ConvertMatrix<double>(Vec3<T>(OpticalAxis()));
    const double denom = d.dot(axis);
    if (std::abs(denom) < 1e-300) return false;
    const double t = (C - Md).dot(axis) / denom;
    if (!(t > 0) || !(t < max_t)) return false;
    return (Md + t * d - C).norm() <= ScalarPart(occluder_radius);
  }

  // Does pixel uv see the mirror: inside the image, inside the rim image, and not the camera's own
  // reflection?
  bool SeesMirror(const Vec2<T>& uv) const {
    if (!camera.InImage(uv)) return false;
    Vec3<T> M, d;
    if (!RayFromImg(uv, &M, &d)) return false;
    return !RayHitsCamera(M, d);
  }

  // The same rig without its visibility limits: the sheet continued to three times the rim's diameter, no
  // camera occluder, no sensor bounds. Its projection is the model's formula wherever that has a value; for
  // solvers over observed points, whose iterates may carry a corner seen near the rim just past it.
  CatadioptricCamera Unbounded() const {
    CatadioptricCamera r = *this;
    r.mirror.rim_diameter = T(3) * r.mirror.rim_diameter;
    r.occluder_radius = T(0);
    r.camera.width = r.camera.height = 0;
    return r;
  }

  void Check(const std::string& where = "catadioptric camera") const {
    mirror.Check(where + ".mirror");
    camera.Check(where + ".camera");
    HOVS_REQUIRE(std::isfinite(ScalarPart(occluder_radius)) && ScalarPart(occluder_radius) >= 0 &&
                     ScalarPart(occluder_radius) <= 10,
                 where, "occluder radius must be a number in [0, 10] m");
    const Eigen::Quaterniond q = cam_from_mirror.rotation.template cast<double>();
    const Vec3d t = ConvertMatrix<double>(cam_from_mirror.translation);
    HOVS_REQUIRE(q.coeffs().allFinite() && std::abs(q.norm() - 1) < 1e-6, where,
                 "cam_from_mirror's rotation must be a unit quaternion");
    HOVS_REQUIRE(t.allFinite() && t.norm() <= 100, where, "cam_from_mirror's translation must be finite, within 100 m");
    const Vec3d C = ConvertMatrix<double>(Vec3<T>(CameraCentre()));
    const HyperboloidMirror<double> md = mirror.template Cast<double>();
    // The pinhole must be outside the mirror body (on the reflective side of the sheet), below the sheet.
    const double g =
        (C(2) + md.c()) * (C(2) + md.c()) / (md.a * md.a) - (C(0) * C(0) + C(1) * C(1)) / (md.b * md.b) - 1.0;
    const bool inside_upper_cup = g > 0 && C(2) + md.c() > 0;
    HOVS_REQUIRE(!inside_upper_cup, where, "the camera centre (", C.transpose(),
                 " m) lies inside the mirror; it must be below the sheet");
  }

  template <class U>
  CatadioptricCamera<U> Cast() const {
    CatadioptricCamera<U> r;
    r.mirror = mirror.template Cast<U>();
    r.camera = camera.template Cast<U>();
    r.cam_from_mirror = cam_from_mirror.template Cast<U>();
    r.occluder_radius = ConvertScalar<U>(occluder_radius);
    return r;
  }

 private:
  ProjectionStatus Finish(const Vec3<T>& X, const Vec3<T>& M, Vec2<T>* uv, Vec3<T>* mirror_point) const {
    if (mirror_point) *mirror_point = M;
    const Vec3d Md = ConvertMatrix<double>(M), Xd = ConvertMatrix<double>(X);
    const Vec3d seg = Xd - Md;
    if (RayHitsCamera(M, Vec3<T>(ConvertMatrix<T>(Vec3d(seg / seg.norm()))), seg.norm()))
      return ProjectionStatus::kOccluded;
    if (!camera.ImgFromCam(cam_from_mirror * M, uv)) return ProjectionStatus::kBehindCamera;
    if (!camera.InImage(*uv)) return ProjectionStatus::kOutsideImage;
    return ProjectionStatus::kOk;
  }
};

}  // namespace hovs
