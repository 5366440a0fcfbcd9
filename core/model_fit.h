// Conversions from an exact design to the calibrated models: the polynomial (OCam) model fitted to an
// aligned hyperboloid rig. (The unified model converts exactly; see unified.h.)
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "core/catadioptric.h"
#include "core/error.h"
#include "core/polynomial.h"

namespace hovs {

// Radii (pixels from the principal point) of the camera's own reflection and of the rim in the image of an
// aligned single-viewpoint rig: the valid annulus.
inline std::pair<double, double> ImageAnnulus(const CatadioptricCamera<double>& rig) {
  HOVS_REQUIRE(rig.IsSingleViewpoint(), "image annulus", "needs a single-viewpoint rig");
  const auto& m = rig.mirror;
  const auto radius_of = [&](const Vec3d& M) {
    Vec2d uv;
    HOVS_REQUIRE(rig.camera.ImgFromCam(rig.cam_from_mirror * M, &uv), "image annulus",
                 "a mirror point projects behind the camera");
    return std::hypot(uv(0) - rig.camera.cx, uv(1) - rig.camera.cy);
  };
  const double rho_max = radius_of(Vec3d(m.RimRadius(), 0, m.RimZ()));
  double rho_min = 0;
  if (rig.occluder_radius > 0) {
    Vec3d M;
    HOVS_REQUIRE(m.PointAlong(Vec3d(rig.occluder_radius, 0, -2 * m.c()), &M), "image annulus",
                 "the camera's reflection is not on the mirror");
    rho_min = radius_of(M);
  }
  return {rho_min, rho_max};
}

// A degree-N polynomial model (a1 = 0) fitted to an aligned rig over its annulus, weighted so that the
// least-squares error is in pixels; the inverse polynomial is fitted too.
inline PolynomialModel<double> PolynomialFromCatadioptric(const CatadioptricCamera<double>& rig, int degree,
                                                          double inverse_tolerance_px = 0.01) {
  HOVS_REQUIRE(degree >= 2 && degree <= 12, "polynomial fit", "degree must be in 2..12 (got ", degree, ")");
  HOVS_REQUIRE(std::abs(rig.camera.fx - rig.camera.fy) < 1e-9 * rig.camera.fx, "polynomial fit",
               "needs square pixels (fx = fy)");
  const auto [rho_min, rho_max] = ImageAnnulus(rig);
  const int n = 2000;
  std::vector<double> rho(n), f(n), theta(n);
  for (int i = 0; i < n; ++i) {
    rho[i] = rho_min + (rho_max - rho_min) * (i + 0.5) / n;
    Vec3d bearing;
    HOVS_REQUIRE(rig.CamFromImg(Vec2d(rig.camera.cx + rho[i], rig.camera.cy), &bearing), "polynomial fit",
                 "a pixel of the annulus does not see the mirror");
    const double norm = std::hypot(bearing(0), bearing(1));
    f[i] = rho[i] * bearing(2) / norm;
    theta[i] = std::atan2(bearing(2), norm);
  }
  // Columns: 1, (rho/s)^2, ..., (rho/s)^N with s = rho_max for conditioning; weights turn f errors into pixels.
  const double s = rho_max;
  Eigen::MatrixXd A(n, degree);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    const int j0 = std::max(0, i - 1), j1 = std::min(n - 1, i + 1);
    const double dtheta = std::abs((theta[j1] - theta[j0]) / (rho[j1] - rho[j0]));
    const double w = rho[i] / ((rho[i] * rho[i] + f[i] * f[i]) * dtheta);
    A(i, 0) = w;
    for (int k = 2; k <= degree; ++k) A(i, k - 1) = w * std::pow(rho[i] / s, k);
    b(i) = w * f[i];
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  PolynomialModel<double> model;
  model.width = rig.camera.width, model.height = rig.camera.height;
  model.cx = rig.camera.cx, model.cy = rig.camera.cy;
  model.poly.assign(degree + 1, 0.0);
  model.poly[0] = x(0);
  for (int k = 2; k <= degree; ++k) model.poly[k] = x(k - 1) / std::pow(s, k);
  model.rho_min = rho_min, model.rho_max = rho_max;
  model.FitInverse(inverse_tolerance_px);
  return model;
}

}  // namespace hovs
