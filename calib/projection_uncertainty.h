// Projection uncertainty of a calibrated model (mrcal's method): how far the calibration's own noise moves the
// projection of a fixed point, propagated from the covariance of the joint solve.
//
// For a pixel q: its ray v = CamFromImg(q) under the solution, the point p = r v at range r (a direction when r is
// infinite). The camera frame is tied to the world only through the boards, so a perturbed solution (intrinsics',
// poses') sees p at
//   p' = mean_i cam'_from_board_i * board_i_from_cam * p      (the mean over the boards of where each puts it)
// and projects it to q' = ImgFromCam(intrinsics', p'). With G = dq'/d(parameters) at the solution and C the
// covariance of every parameter (intrinsics and poses, sigma estimated from the residuals), the pixel's 2 x 2
// covariance is G C G^T. Reported per pixel: the worst-direction standard deviation of q' (px), and of the ray
// (degrees): the same at infinite range, turned into an angle through the projection's local Jacobian.
// A gauge freedom of the solve (a rotation about the axis that the affine terms absorb) moves no projection, so
// the pseudo-inverse covariance gives the same result as any other generalised inverse.
#pragma once

#include <Eigen/Dense>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "calib/model_diff.h"
#include "core/polynomial.h"
#include "core/rigid.h"
#include "core/unified.h"

namespace hovs::calib {

// The covariance of a solve's free parameters in the order the propagation needs: the model's intrinsics
// (ParametricModel's order), then 6 per board pose (angle-axis of cam_from_board, then its translation).
struct SolveCovariance {
  Eigen::MatrixXd covariance;           // empty when the solve's covariance was not computable
  std::vector<Rigid3d> cam_from_board;  // the solution's poses
  double sigma_px = 0;                  // the residual standard deviation the covariance is scaled by
  bool valid() const { return covariance.size() > 0; }
};

// A calibrated model as a vector of intrinsics:
//   polynomial: cx, cy, c, d, e, a0, a2, ..., aN      unified: xi, fx, fy, cx, cy, k1, k2, p1, p2
class ParametricModel {
 public:
  explicit ParametricModel(const PolynomialModel<double>& model);
  explicit ParametricModel(const UnifiedModel<double>& model);
  int size() const { return static_cast<int>(values_.size()); }
  int width() const;
  int height() const;
  // The nominal model's ray and projection.
  bool CamFromImg(const Vec2d& uv, Vec3d* ray) const;
  bool ImgFromCam(const Vec3d& p, Vec2d* uv) const;
  // The projection and its Jacobians with respect to the intrinsics (2 x size) and to the point (2 x 3).
  bool ImgFromCamJacobians(const Vec3d& p, Vec2d* uv, Eigen::MatrixXd* d_intrinsics,
                           Eigen::Matrix<double, 2, 3>* d_point) const;

 private:
  std::variant<PolynomialModel<double>, UnifiedModel<double>> model_;
  std::vector<double> values_;
};

struct PixelUncertainty {
  double px = 0;                                             // worst-direction standard deviation of q', pixels
  double deg = 0;                                            // of the ray, degrees
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();      // of q', px^2
  Eigen::Matrix2d ray_covariance = Eigen::Matrix2d::Zero();  // of the ray in its tangent plane, rad^2
};

// dq'/d(parameters) at the point p of the solution's camera frame (a direction when `infinite`): 2 x (intrinsics
// + 6 per pose), the poses' columns carrying the 1 / n of the mean; and the projection's Jacobian dq/dp.
bool ProjectionGradient(const ParametricModel& model, const std::vector<Rigid3d>& cam_from_board, const Vec3d& p,
                        bool infinite, Eigen::MatrixXd* G, Eigen::Matrix<double, 2, 3>* d_point);

// d(R(aa) b)/d(aa) at the angle-axis `aa` (3 x 3): how a pose's rotation parameters move a point b of its frame.
Eigen::Matrix3d RotatedPointJacobian(const double* aa, const Vec3d& b);

// range_m 0: at infinity. Empty when the pixel has no ray or the point does not project back.
std::optional<PixelUncertainty> ProjectionUncertainty(const ParametricModel& model, const SolveCovariance& solve,
                                                      const Vec2d& uv, double range_m);

struct UncertaintyOptions {
  double range_m = 0;    // the range of the px map; 0: infinity
  int grid_step_px = 0;  // 0: about 120 grid columns
  double rho_min = 0;    // the map covers the annulus rho_min..rho_max around (cx, cy) (the calibrated field);
  double rho_max = 0;    // rho_max 0: every pixel the model has a ray for
  Vec2d centre = Vec2d::Zero();
  void Check(const std::string& where) const;
};

struct UncertaintyMap : ImageGrid {
  std::vector<double> px, deg;  // ny rows of nx; NaN outside the map's domain
  SampleSummary px_stats, deg_stats;
  double range_m = 0, sigma_px = 0;
};

// Throws hovs::Error when the covariance is missing or does not match the model and its poses.
UncertaintyMap ProjectionUncertaintyMap(const ParametricModel& model, const SolveCovariance& solve,
                                        const UncertaintyOptions& options);

nlohmann::json UncertaintyJson(const UncertaintyMap& map);

// Two maps (px at the range, degrees) under `title`.
void WriteUncertaintyFigures(const UncertaintyMap& map, const std::string& title, const std::filesystem::path& px_png,
                             const std::filesystem::path& deg_png);

}  // namespace hovs::calib
