// Monocular calibration of the polynomial (OCamCalib) model from board-corner correspondences:
// Scaramuzza's linear initialisation (centre fixed, R and t from the cross-product constraint, then the
// polynomial and t3 by linear least squares), then one joint Ceres problem over the centre, the affine terms
// c, d, e, the polynomial a0, a2..aN and every board pose, with 2-D reprojection residuals through the core's
// exact world2cam and an optional robust loss. Standard deviations and the covariance used for the projection
// uncertainty (calib/projection_uncertainty.h) come from the Jacobian at the solution (calib/solver_util.h).
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calib/board_warp.h"
#include "calib/projection_uncertainty.h"
#include "core/polynomial.h"
#include "core/rigid.h"

namespace hovs::calib {

// One image's corners: points on the board (board frame, z = 0, metres) and their pixels.
struct BoardObservation {
  std::string image;
  std::vector<Vec3d> board_points;
  std::vector<Vec2d> pixels;
};

struct PolynomialCalibrationOptions {
  int degree = 4;                       // N; a1 = 0
  std::string loss = "none";            // none | huber | cauchy
  double loss_scale = 1.0;              // pixels
  bool estimate_affine = true;          // c, d, e
  std::optional<Vec2d> initial_centre;  // default: the image centre
  int max_iterations = 200;
  // Outlier rejection after the first solve: corners above max(outlier_floor_px, outlier_sigmas x the robust
  // per-axis sigma of all residuals) are removed and listed, and the problem is solved again. 0 disables it.
  double outlier_sigmas = 5;
  double outlier_floor_px = 0.5;
  // Estimate the board's flex (calib/board_warp.h: two parabolas shared by every image) in the joint solve.
  bool board_flex = false;
  bool board_flex_per_image = false;  // with board_flex: one warp per image instead of one for all
  // Estimate the decentering p1, p2 (core/polynomial.h; hovs' extension: OCamCalib's calib_results.txt cannot
  // hold it, so a model with it is not written in that format).
  bool estimate_decentering = false;
  void Check(const std::string& where) const;
};

// A corner the solve rejected: its residual after the first solve, and after the final solve (not used by it).
struct CornerOutlier {
  int image_index = 0;
  std::string image;
  int corner = 0;
  double residual_px = 0;
  double residual_after_px = 0;
};

struct PolynomialCalibration {
  PolynomialModel<double> model;
  std::vector<Rigid3d> cam_from_board;             // the board poses, in the model's (mirror) frame
  std::vector<double> per_image_rms;               // px, over the image's inliers
  std::vector<double> per_image_mean;              // px, mean reprojection error (the article's figure)
  double rms = 0, mean = 0;                        // over all inlier corners, px
  std::vector<std::vector<bool>> inlier;           // per image, per corner
  std::vector<CornerOutlier> outliers;             // rejected corners, listed
  double outlier_threshold_px = 0;                 // 0: rejection disabled
  double initial_rms = 0;                          // after the linear initialisation
  std::map<std::string, double> stddev;            // cx, cy, c, d, e, a0, a2, ... (from the covariance)
  SolveCovariance covariance;                      // intrinsics (cx, cy, c, d, e, a0, a2, ...) and poses
  bool board_flex = false;                         // estimated (else board_warp is 0)
  std::array<double, 2> board_warp = {0, 0};       // metres (calib/board_warp.h); per image: their mean
  std::vector<std::array<double, 2>> image_warps;  // per image (board_flex_per_image), else empty
  const std::array<double, 2>& WarpOf(size_t image) const {
    return image < image_warps.size() ? image_warps[image] : board_warp;
  }
  BoardExtent board_extent;
  bool converged = false;
  std::string solver_report;
};

// Throws hovs::Error for fewer than three images, images with fewer than 6 corners, degenerate data.
PolynomialCalibration CalibratePolynomial(const std::vector<BoardObservation>& observations, int width, int height,
                                          const PolynomialCalibrationOptions& options);

// The observations without the corners the calibration rejected (same images, same order).
std::vector<BoardObservation> InlierObservations(const std::vector<BoardObservation>& observations,
                                                 const PolynomialCalibration& calibration);

// Reads a corner table: image,corner,board_x_mm,board_y_mm,u_px,v_px (the format of shared/data/vmr).
std::vector<BoardObservation> LoadCornerCsv(const std::filesystem::path& path);
std::vector<BoardObservation> ParseCornerCsv(const std::string& text, const std::string& where);

}  // namespace hovs::calib

#include "core/unified.h"

namespace hovs::calib {

struct UnifiedCalibration {
  UnifiedModel<double> model;
  std::vector<Rigid3d> cam_from_board;
  std::vector<double> per_image_rms;
  double rms = 0, mean = 0;
  std::map<std::string, double> stddev;            // xi, fx, fy, cx, cy, k1, k2, p1, p2 (from the covariance)
  SolveCovariance covariance;                      // intrinsics (xi, fx, fy, cx, cy, k1, k2, p1, p2) and poses
  std::array<double, 2> board_warp = {0, 0};       // metres, estimated when the polynomial start estimated it (mean)
  std::vector<std::array<double, 2>> image_warps;  // per image, when the start has them
  bool converged = false;
  std::string solver_report;
};

// The unified (Mei) model with radial-tangential distortion through the same machinery: started from a
// polynomial calibration (its poses, and a unified model fitted to its rays), then one joint Ceres problem over
// xi, fx, fy, cx, cy, k1, k2, p1, p2 (distortion held at 0 unless estimate_distortion) and every pose.
// With the distortion free, xi, the focal lengths and k1 trade off along a shallow valley (Mei's model is
// nearly degenerate there): their standard deviations are large and only the centre is well determined.
UnifiedCalibration CalibrateUnified(const std::vector<BoardObservation>& observations, int width, int height,
                                    const PolynomialCalibration& start, const std::string& loss = "none",
                                    double loss_scale = 1.0, bool estimate_distortion = true);

}  // namespace hovs::calib
