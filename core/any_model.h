// One handle on any catadioptric model of the core: the exact rig (hyperboloid + pinhole + pose), the
// polynomial (OCam) model or the unified (Mei) model. Unwrapping and depth take this handle, so they run the
// same way on the design, on a calibration and on a real camera's model.
//
// Bearings are unit vectors in the mirror frame (conventions.h), seen from the viewpoint F1.
// Validity of a pixel (each model's own domain, plus the image):
//   exact       the pixel's ray meets the mirror inside the rim and does not see the camera (SeesMirror);
//               a bearing projects when the law of reflection has a solution inside the rim, not occluded by
//               the camera (ProjectionStatus::kOk). For a rig that is not single-viewpoint the projection
//               depends on depth: bearings are projected as points at `scene_distance` metres from F1.
//   polynomial  rho_min <= rho <= rho_max (the calibrated annulus) and inside the image.
//   unified     inside the annulus (centre cx, cy; radii annulus_min, annulus_max in pixels) when annulus_max
//               is set, and inside the image.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/catadioptric.h"
#include "core/error.h"
#include "core/polynomial.h"
#include "core/unified.h"

namespace hovs {

class AnyModel {
 public:
  enum class Kind { kExact, kPolynomial, kUnified };

  // where: the model's source (a file) in errors.
  static AnyModel Exact(const CatadioptricCamera<double>& rig, double scene_distance = 10.0,
                        const std::string& where = "exact model") {
    rig.Check(where);
    HOVS_REQUIRE(rig.camera.width > 0 && rig.camera.height > 0, where, "the camera needs an image size");
    HOVS_REQUIRE(scene_distance > 0 && scene_distance <= 1e6, where + " (scene distance)",
                 "must be in (0, 1e6] m (got ", scene_distance, ")");
    AnyModel m;
    m.kind_ = Kind::kExact;
    m.exact_ = rig;
    m.unbounded_ = rig.Unbounded();
    m.scene_distance_ = scene_distance;
    m.svp_ = rig.IsSingleViewpoint();
    m.width_ = rig.camera.width, m.height_ = rig.camera.height;
    return m;
  }
  static AnyModel Polynomial(const PolynomialModel<double>& model, const std::string& where = "polynomial model") {
    model.Check(where);
    HOVS_REQUIRE(model.width > 0 && model.height > 0, where, "needs the image size");
    HOVS_REQUIRE(model.rho_max > model.rho_min, where, "needs a valid annulus (rho_min < rho_max)");
    AnyModel m;
    m.kind_ = Kind::kPolynomial;
    m.poly_ = model;
    m.width_ = model.width, m.height_ = model.height;
    return m;
  }
  // annulus_max <= 0: no annulus (the whole image is valid where the model is).
  static AnyModel Unified(const UnifiedModel<double>& model, double annulus_min = 0, double annulus_max = 0,
                          const std::string& where = "unified model") {
    model.Check(where);
    HOVS_REQUIRE(model.width > 0 && model.height > 0, where, "needs the image size");
    HOVS_REQUIRE(std::isfinite(annulus_min) && std::isfinite(annulus_max) && annulus_min >= 0 &&
                     annulus_max <= 2.0 * (model.width + model.height),
                 where, "the annulus [", annulus_min, ", ", annulus_max, "] px does not fit the image");
    AnyModel m;
    m.kind_ = Kind::kUnified;
    m.unified_ = model;
    m.annulus_ = {annulus_min, annulus_max};
    m.width_ = model.width, m.height_ = model.height;
    return m;
  }

  Kind kind() const { return kind_; }
  const char* KindName() const {
    return kind_ == Kind::kExact ? "exact" : kind_ == Kind::kPolynomial ? "polynomial" : "unified";
  }
  int width() const { return width_; }
  int height() const { return height_; }
  const CatadioptricCamera<double>& exact() const { return exact_; }
  const PolynomialModel<double>& polynomial() const { return poly_; }
  const UnifiedModel<double>& unified() const { return unified_; }
  double scene_distance() const { return scene_distance_; }
  std::pair<double, double> annulus() const { return annulus_; }

  bool InImage(const Vec2d& uv) const {
    return uv(0) >= -0.5 && uv(1) >= -0.5 && uv(0) <= width_ - 0.5 && uv(1) <= height_ - 0.5;
  }

  // Pixel of a bearing (mirror frame, any length); false outside the model's valid domain.
  bool ImgFromMirror(const Vec3d& bearing, Vec2d* uv) const {
    switch (kind_) {
      case Kind::kExact: {
        const Vec3d X = bearing.normalized() * scene_distance_;
        const ProjectionStatus s = svp_ ? exact_.ImgFromMirrorSvp(X, uv) : exact_.ImgFromMirrorGeneral(X, uv);
        return s == ProjectionStatus::kOk;
      }
      case Kind::kPolynomial: {
        if (!poly_.ImgFromCam(bearing, uv)) return false;
        const double rho = poly_.RhoOfImg(*uv);
        return rho >= poly_.rho_min && rho <= poly_.rho_max && InImage(*uv);
      }
      case Kind::kUnified:
        if (!unified_.ImgFromCam(bearing, uv)) return false;
        return InAnnulus(*uv) && InImage(*uv);
    }
    return false;
  }

  // ImgFromMirror of `count` bearings (row-major count x 3 in, count x 2 out). The polynomial model projects
  // them in blocks (PolynomialModel::ImgFromCamBatch); the others one by one.
  void ImgFromMirrorBatch(const double* bearings, std::size_t count, double* uv, bool* ok) const {
    if (kind_ != Kind::kPolynomial) {
      for (std::size_t i = 0; i < count; ++i) {
        Vec2d q(0, 0);
        ok[i] = ImgFromMirror(Vec3d(bearings[3 * i], bearings[3 * i + 1], bearings[3 * i + 2]), &q);
        uv[2 * i] = q(0), uv[2 * i + 1] = q(1);
      }
      return;
    }
    poly_.ImgFromCamBatch(bearings, count, uv, ok);
    for (std::size_t i = 0; i < count; ++i) {
      if (!ok[i]) continue;
      const Vec2d q(uv[2 * i], uv[2 * i + 1]);
      const double rho = poly_.RhoOfImg(q);
      ok[i] = rho >= poly_.rho_min && rho <= poly_.rho_max && InImage(q);
    }
  }

  // Pixel of a point X (mirror frame, metres) by the model's formula without its validity domain (exact:
  // CatadioptricCamera::Unbounded, the sheet continued past the rim, no camera occlusion; polynomial: any rho;
  // unified: no annulus; no image bounds): false only where the formula has no value (a direction that misses
  // the sheet, a point behind the camera or the mirror). The exact model of a rig that is not single-viewpoint
  // projects X itself, at its own distance (not at scene_distance: the point is known). For solvers over board
  // points, whose iterates may carry a corner observed near the rim just past it: ImgFromMirror would fail there
  // instead of pulling it back.
  bool ImgFromPointUnbounded(const Vec3d& X, Vec2d* uv) const {
    switch (kind_) {
      case Kind::kExact:
        return (svp_ ? unbounded_.ImgFromMirrorSvp(X, uv) : unbounded_.ImgFromMirrorGeneral(X, uv)) ==
               ProjectionStatus::kOk;
      case Kind::kPolynomial: return poly_.ImgFromCam(X, uv);
      case Kind::kUnified: return unified_.ImgFromCam(X, uv);
    }
    return false;
  }

  // Unit bearing (mirror frame) of a pixel; false outside the valid domain.
  bool MirrorFromImg(const Vec2d& uv, Vec3d* bearing) const {
    if (!InImage(uv)) return false;
    switch (kind_) {
      case Kind::kExact: {
        Vec3d M, d;
        if (!exact_.RayFromImg(uv, &M, &d) || exact_.RayHitsCamera(M, d)) return false;
        *bearing = d;
        return true;
      }
      case Kind::kPolynomial: {
        const double rho = poly_.RhoOfImg(uv);
        if (rho < poly_.rho_min || rho > poly_.rho_max) return false;
        return poly_.CamFromImg(uv, bearing);
      }
      case Kind::kUnified: return InAnnulus(uv) && unified_.CamFromImg(uv, bearing);
    }
    return false;
  }

  // The view ray of a pixel (mirror frame): its origin and unit direction; false outside the valid domain (as
  // MirrorFromImg). The exact model's ray starts where it leaves the mirror, which for a rig that is not
  // single-viewpoint is off the line through F1; the central models' rays start at F1 (the origin).
  bool RayFromImg(const Vec2d& uv, Vec3d* origin, Vec3d* direction) const {
    if (kind_ != Kind::kExact) {
      *origin = Vec3d::Zero();
      return MirrorFromImg(uv, direction);
    }
    Vec3d M, d;
    if (!InImage(uv) || !exact_.RayFromImg(uv, &M, &d) || exact_.RayHitsCamera(M, d)) return false;
    *origin = svp_ ? Vec3d::Zero() : M;
    *direction = d;
    return true;
  }

  // Named parameters (for headers of mapping files and reports).
  std::vector<std::pair<std::string, double>> Parameters() const {
    std::vector<std::pair<std::string, double>> p;
    switch (kind_) {
      case Kind::kExact: {
        const auto& r = exact_;
        const Vec3d C = r.CameraCentre();
        const auto& q = r.cam_from_mirror.rotation;
        p = {{"a", r.mirror.a},
             {"b", r.mirror.b},
             {"rim_diameter", r.mirror.rim_diameter},
             {"fx", r.camera.fx},
             {"fy", r.camera.fy},
             {"cx", r.camera.cx},
             {"cy", r.camera.cy},
             {"k1", r.camera.distortion.k1},
             {"k2", r.camera.distortion.k2},
             {"p1", r.camera.distortion.p1},
             {"p2", r.camera.distortion.p2},
             {"qw", q.w()},
             {"qx", q.x()},
             {"qy", q.y()},
             {"qz", q.z()},
             {"camera_x", C(0)},
             {"camera_y", C(1)},
             {"camera_z", C(2)},
             {"occluder_radius", r.occluder_radius},
             {"scene_distance", scene_distance_}};
        break;
      }
      case Kind::kPolynomial: {
        p = {{"cx", poly_.cx},           {"cy", poly_.cy},          {"c", poly_.c}, {"d", poly_.d}, {"e", poly_.e},
             {"rho_min", poly_.rho_min}, {"rho_max", poly_.rho_max}};
        for (size_t i = 0; i < poly_.poly.size(); ++i) p.emplace_back("a" + std::to_string(i), poly_.poly[i]);
        for (size_t i = 0; i < poly_.inv_poly.size(); ++i) p.emplace_back("inv" + std::to_string(i), poly_.inv_poly[i]);
        break;
      }
      case Kind::kUnified: {
        const auto& u = unified_;
        p = {{"xi", u.xi},
             {"fx", u.fx},
             {"fy", u.fy},
             {"cx", u.cx},
             {"cy", u.cy},
             {"skew", u.skew},
             {"k1", u.distortion.k1},
             {"k2", u.distortion.k2},
             {"p1", u.distortion.p1},
             {"p2", u.distortion.p2},
             {"annulus_min", annulus_.first},
             {"annulus_max", annulus_.second}};
        break;
      }
    }
    p.emplace_back("width", width_);
    p.emplace_back("height", height_);
    return p;
  }

 private:
  bool InAnnulus(const Vec2d& uv) const {
    if (annulus_.second <= 0) return true;
    const double r = std::hypot(uv(0) - unified_.cx, uv(1) - unified_.cy);
    return r >= annulus_.first && r <= annulus_.second;
  }

  Kind kind_ = Kind::kExact;
  CatadioptricCamera<double> exact_, unbounded_;  // unbounded_: exact_.Unbounded(), for ImgFromPointUnbounded
  PolynomialModel<double> poly_;
  UnifiedModel<double> unified_;
  std::pair<double, double> annulus_{0, 0};
  double scene_distance_ = 10.0;
  bool svp_ = true;
  int width_ = 0, height_ = 0;
};

}  // namespace hovs
