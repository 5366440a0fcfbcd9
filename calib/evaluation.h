// Calibrated models against the exact rig of a synthetic dataset: how far the calibrated rays are from the true
// ones, and how far detected corners are from the exact corners. Used by hovs calibrate, hovs validate and any
// study that repeats a calibration (Monte Carlo, a Slurm shard, the Python binding).
#pragma once

#include <vector>

#include "core/catadioptric.h"
#include "core/polynomial.h"

namespace hovs::calib {

// Ray angles of a central (single-viewpoint) model against the true rig over the pixels where both apply: the
// true direction, from F1, of the point each pixel sees at `distance` (a misaligned rig is not single-viewpoint,
// so a central model can only be right for points at some distance), against the model's bearing. Also after
// the best rotation of the model's frame onto the true one: a monocular calibration fixes its frame only through
// the model's symmetry, so a small tilt of the whole frame is nearly unobservable and harmless downstream
// (stereo calibration estimates the relative pose of the calibrated frames).
struct RayAccuracy {
  int pixels = 0;  // compared pixels; 0: no figure (the model's annulus misses the mirror)
  double mean_deg = 0, max_deg = 0;
  double mean_aligned_deg = 0, max_aligned_deg = 0;
  double frame_rotation_deg = 0;  // the rotation removed
};

struct RayAccuracyOptions {
  double distance = 2.0;  // m, along each true ray from its mirror point
  int min_step = 4;       // pixel grid: every max(min_step, width / columns) pixels
  int columns = 110;
};

RayAccuracy CompareWithTruth(const CatadioptricCamera<double>& truth, const PolynomialModel<double>& model,
                             const RayAccuracyOptions& options = {});

// A calibrated physical rig (mirror + camera pose, exact projection) against the true one: ray angles over the
// whole true mirror image, the tilt error (the rotation between the two cam_from_mirror) and the distance between
// the camera centres.
struct PhysicalAccuracy {
  int pixels = 0;
  double mean_deg = 0, max_deg = 0;
  double tilt_error_deg = 0, centre_error_m = 0;
};

PhysicalAccuracy CompareWithTruth(const CatadioptricCamera<double>& truth, const CatadioptricCamera<double>& calibrated,
                                  const RayAccuracyOptions& options = {});

// Detected corners against the exact ones: each detected corner against its nearest true corner (the detector
// does not number corners the way the renderer does).
struct CornerAccuracy {
  double rms_px = 0, max_px = 0;
};

CornerAccuracy CompareWithTruth(const std::vector<Vec2d>& detected, const std::vector<Vec2d>& truth);

}  // namespace hovs::calib
