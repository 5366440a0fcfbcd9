// Binocular depth from two catadioptric units: sparse triangulation and dense spherical stereo.
//
// Frames: each unit's model works in its own mirror frame (origin at its viewpoint F1). The rig gives
// right_from_left (mirror frame to mirror frame); the baseline B is |F1_right - F1_left|.
//
// Sparse: the two bearings of one world point are intersected (midpoint of the common perpendicular, the
// general form of the article's law of sines: with parallel axes and horizontal rays it reduces to
// r_left = B sin(theta_right) / sin(theta_right - theta_left), theta the angles to the baseline). The per-point
// uncertainty propagates an isotropic angular noise sigma (radians) on each bearing to the range.
//
// Dense: both units are rectified into epipolar views (core/virtual_view.h, ViewProjection::kEpipolar) that
// share the baseline as pole and one orientation: each plane through the baseline is one row, column u gives
// the angle theta between the ray and the baseline (decreasing to the right). A point seen at column u_L in the
// left view and u_R in the right has disparity d = u_L - u_R >= 0 (columns), angular disparity
// delta = d * dtheta, and range from the left viewpoint
//   r_L = B sin(theta_L + delta) / sin(delta)              (law of sines; not B f / d)
//   sigma_r = B sin(theta_L) / sin^2(delta) * sigma_delta  (sigma_delta = sigma_d * dtheta).
// Depth is ill-conditioned near the baseline direction (theta near 0 or 180 degrees) and where sigma_r / r is
// large: those pixels are masked.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "core/rigid.h"
#include "unwrap/remap.h"

namespace hovs::depth {

struct StereoRig {
  AnyModel left, right;
  Rigid3d right_from_left;  // mirror frame of the left unit -> mirror frame of the right unit
  Vec3d RightCentreInLeft() const { return right_from_left.Inverse().translation; }
  double Baseline() const { return RightCentreInLeft().norm(); }
};

// ---- sparse ----------------------------------------------------------------------------------------------
struct Triangulation {
  bool ok = false;
  Vec3d point_left = Vec3d::Zero();  // left mirror frame
  double range_left = 0;             // from the left viewpoint, m
  double sigma_range = 0;            // m, from the angular noise
  double gap = 0;                    // distance between the two rays at their closest points, m
};
// Bearings in each unit's mirror frame (any length), from its viewpoint F1. Fails for (near-)parallel rays or a
// point behind a unit.
Triangulation Triangulate(const StereoRig& rig, const Vec3d& bearing_left, const Vec3d& bearing_right,
                          double sigma_angle_rad);
// The same for rays with their own origins (each unit's mirror frame): the rays of a unit that is not
// single-viewpoint start on its mirror, not at F1 (AnyModel::RayFromImg).
Triangulation Triangulate(const StereoRig& rig, const Vec3d& origin_left, const Vec3d& bearing_left,
                          const Vec3d& origin_right, const Vec3d& bearing_right, double sigma_angle_rad);

// The article's closed form (horizontal rays, parallel axes): range from the left viewpoint given the angles
// to the baseline at both units. Exposed for tests and reports.
double LawOfSinesRange(double baseline, double theta_left, double theta_right);

// ---- rectification -------------------------------------------------------------------------------------
struct RectifyOptions {
  int width = 2048, height = 512;
  double theta_min_deg = 5, theta_max_deg = 175;  // angle from the baseline (columns)
  double phi_min_deg = -180, phi_max_deg = 0;     // angle around the baseline (rows): the lower half-space
  void Check(const std::string& where) const;
};

struct Rectification {
  RectifyOptions options;
  double baseline = 0;
  Eigen::Quaterniond left_from_rect, right_from_rect;  // the shared epipolar frame (x = baseline)
  unwrap::RemapTable left, right;                      // one epipolar view each
  double dtheta = 0;                                   // radians per column
  double ThetaAt(double u) const;                      // angle from the baseline of column u
  // Left mirror-frame bearing of a rectified pixel.
  Vec3d LeftBearing(double u, double v) const;
};
Rectification Rectify(const StereoRig& rig, const RectifyOptions& options);

// ---- dense ------------------------------------------------------------------------------------------------
struct DenseOptions {
  int num_disparities = 320;         // columns, multiple of 16 (at 0.088 deg per column: ranges down to 1.3 m)
  int block_size = 5;                // odd
  double sigma_disparity_px = 0.5;   // matching noise assumed for sigma
  double min_theta_deg = 12;         // mask rays closer than this to the baseline direction
  double max_relative_sigma = 0.05;  // mask where sigma_r / r exceeds this
  // Coarse to fine: SGBM on both images at half resolution (half the disparities: an eighth of the full cost),
  // then each pixel refined at full resolution by a block search (SAD of the block_size window on intensity
  // and horizontal gradient) over refine_radius columns around twice its coarse disparity, with a parabola
  // through the best cost and its neighbours; where the best cost lies at the edge of the search, the coarse
  // disparity is kept.
  bool coarse_to_fine = true;
  int refine_radius = 3;
  void Check(const std::string& where) const;
};

struct DenseDepth {
  int width = 0, height = 0;
  std::vector<float> disparity;  // columns (left reference); < 0 where no match
  std::vector<float> range;      // m from the left viewpoint; NaN where masked
  std::vector<float> sigma;      // m; NaN where masked
  std::vector<uint8_t> valid;    // 1 where range is given
  double match_ms = 0, total_ms = 0;
};
// left_rect and right_rect: the two rectified views (grey or RGB, 8-bit).
DenseDepth ComputeDenseDepth(const Rectification& r, const unwrap::Image8& left_rect, const unwrap::Image8& right_rect,
                             const DenseOptions& options);

// Range from an angular disparity, and its sigma (the formulas above).
double RangeFromDisparity(double baseline, double theta_left, double delta);
double RangeSigma(double baseline, double theta_left, double delta, double sigma_delta);

// ---- output ----------------------------------------------------------------------------------------------
struct ColouredPoint {
  Vec3d p;
  std::array<uint8_t, 3> rgb{{200, 200, 200}};
};
// Point clouds in the left mirror frame: ASCII PLY and VTK PolyData (.vtp, with a "range" and "sigma" array
// when given); atomic writes.
void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points);
void WriteVtp(const std::filesystem::path& path, const std::vector<ColouredPoint>& points,
              const std::vector<float>& sigma = {});
// Range and sigma as a two-channel float OpenEXR (channels Z and Z.sigma), atomic.
void WriteRangeExr(const std::filesystem::path& path, const DenseDepth& d,
                   const std::vector<std::pair<std::string, std::string>>& metadata);

}  // namespace hovs::depth
