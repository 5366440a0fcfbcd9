// Binocular calibration with an ArUco marker board (the article's 3.2.2, done right).
//
// Detection: ArUco knows no catadioptric camera, so each image is unwrapped into overlapping virtual
// perspective views (a ring of views around the mirror axis), markers are detected there with sub-pixel corner
// refinement, and every corner is mapped back to the catadioptric image through the same model (the source
// pixel the view shows at that position), then refined there: cornerSubPix, then (by default) the
// intersection of the marker's two sides measured along their whole length (depth/marker_edges.h), which
// the marker's inner bits cannot bias; corners that move more than max_refine_shift_px are dropped. A marker seen in
// two views keeps the detection nearest a view centre.
//
// Calibration: per pair, each unit's board pose starts from PnP in the view that holds the most markers; then
// one Ceres problem over all pairs: the relative pose right_from_left (rotation as a quaternion on its
// manifold) and left_from_board per pair, with 2-D reprojection residuals of every corner through both
// catadioptric models (the law-of-reflection projection for a misaligned exact rig), and a robust (Huber) loss.
// Pairs may show different marker subsets in the two units. Corners with a residual above outlier_px after
// the first solve are dropped and listed, and the problem is solved again. Standard deviations of the baseline, the
// offsets and the rotation angles come from the covariance.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "core/rigid.h"
#include "unwrap/remap.h"

namespace hovs::depth {

struct MarkerDetectOptions {
  std::string dictionary = "DICT_6X6_250";
  int views = 8;  // perspective views around the axis (yaw step 360 / views)
  double pitch_deg = -25, hfov_deg = 80;
  int width = 1000, height = 750;
  int refine_window = 4;             // half size (px) of the corner refinement in the catadioptric image
  double max_refine_shift_px = 1.5;  // corners the refinement moves further are dropped
  // "edges": each corner where the marker's two sides, measured along their length and fitted, meet
  // (depth/marker_edges.h; corners whose sides do not measure well keep the cornerSubPix result);
  // "subpix": cornerSubPix only.
  std::string corner_refinement = "edges";
  void Check(const std::string& where) const;
};

// One detected marker corner: corner id = 4 * marker id + k (k as OpenCV orders a marker's corners).
struct CornerObservation {
  int id = 0;
  Vec2d pixel = Vec2d::Zero();  // catadioptric image
  bool from_edges = false;      // refined from the marker's edges (else by the corner window)
};

class MarkerDetector {
 public:
  MarkerDetector(const AnyModel& model, const MarkerDetectOptions& options);  // builds the view tables
  // image: 8-bit grey or RGB of the model's size. Throws on a size mismatch.
  std::vector<CornerObservation> Detect(const unwrap::Image8& image) const;
  int views() const { return static_cast<int>(table_.views.size()); }

 private:
  AnyModel model_;
  MarkerDetectOptions options_;
  unwrap::RemapTable table_;
};

struct StereoPairObservation {
  std::string name;
  std::vector<CornerObservation> left, right;
};

struct StereoCalibrationOptions {
  double huber_px = 1.0;
  int min_common_markers = 1;  // pairs need at least this many markers seen by both units
  int max_iterations = 200;
  double outlier_px = 3.0;  // corners with a larger residual after the first solve are dropped (0: keep all)
  // "reprojection" (default): the joint problem above. "3d": the article's method for comparison: each unit's
  // board pose on its own (BoardPose), then right_from_left alone from the 3-D residual
  // right_from_left * P_left - P_right (metres) of every corner both units saw; no reprojection, no outlier pass.
  std::string residual = "reprojection";
  void Check(const std::string& where) const;
};

struct StereoOutlier {
  std::string pair, unit;  // unit: "left" or "right"
  int corner = 0;
  double residual_px = 0;
};

struct StereoCalibration {
  Rigid3d right_from_left;
  double baseline = 0;                       // m
  double sigma_baseline = 0;                 // m
  Vec3d sigma_translation = Vec3d::Zero();   // m, components of right_from_left.translation
  Vec3d sigma_rotation_deg = Vec3d::Zero();  // about x, y, z (tangent space of the rotation)
  double rms_px = 0;
  std::vector<std::string> pair_names;
  std::vector<double> pair_rms_left_px, pair_rms_right_px;
  std::vector<int> pair_corners_left, pair_corners_right;
  std::vector<Rigid3d> left_from_board;
  std::vector<StereoOutlier> outliers;  // dropped after the first solve, listed
  std::string residual = "reprojection";
  double rms_3d_m = 0;  // "3d": RMS of the 3-D residual
  bool converged = false;
  std::string solver_report;
};

// board: corner id -> point in the board frame (metres). Throws hovs::Error naming the problem for fewer than
// two usable pairs, pairs without common markers, or a failed solve.
StereoCalibration CalibrateStereo(const AnyModel& left, const AnyModel& right,
                                  const std::vector<StereoPairObservation>& pairs, const std::map<int, Vec3d>& board,
                                  const StereoCalibrationOptions& options);

// Pose of the board in one unit's mirror frame from its corners (PnP in a virtual view, then refined through
// the catadioptric model). False when fewer than 4 corners or the solve fails.
bool BoardPose(const AnyModel& model, const std::vector<CornerObservation>& corners, const std::map<int, Vec3d>& board,
               Rigid3d* mirror_from_board, double* rms_px);

// Per-marker consistency against the board: the board pose from all corners, then, worst first, every marker
// with a corner further than max_px from the pose's reprojection is removed from `corners` and the pose solved
// again (a marker partly hidden by the other unit can still decode, with corners at hidden positions). Returns
// the removed marker ids. Nothing is removed when fewer than 3 markers (or no pose) remain.
std::vector<int> RejectInconsistentMarkers(const AnyModel& model, std::vector<CornerObservation>* corners,
                                           const std::map<int, Vec3d>& board, double max_px = 2.0);

}  // namespace hovs::depth
