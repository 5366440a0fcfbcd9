// The mounting plate's pose from one image of its fiducial label: the ArUco markers on the plate's underside are
// detected, their corners refined from the markers' edges (depth/marker_edges.h), and the plate's pose solved by
// PnP with the camera's own intrinsics (the lens is calibrated without the mirror; in simulation they are exact).
// Unlike the rim, which moves alike for a tilt and a lateral offset, the label gives all six degrees of freedom:
// lateral offset, height, tilt and the turret's yaw, separately.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "rig/turret.h"

namespace hovs::rig {

struct LabelOptions {
  int min_markers = 3;      // fewer: the label counts as not seen (covered, out of view)
  double max_rms_px = 1.0;  // reprojection RMS above this: the measurement is refused
  void Check(const std::string& where) const;
};

struct LabelMeasurement {
  MirrorPose pose;  // of mirror k, in its nominal frame
  int markers = 0;  // label markers used
  double rms_px = 0;
  std::vector<int> ids;
  // 1 sigma of the measured offset (m: x, y, z) and rotation (rad: about x, y) from the corners' scatter: the
  // PnP fit's covariance sigma^2 (J^T J)^-1 with sigma^2 the residuals' sum of squares over their degrees of
  // freedom, carried to the pose by the fit's own Jacobian. It grows with the pixel size: a camera downscaled 5
  // times measures the tilt some 5 times coarser (and its corners less sharply).
  std::array<double, 5> sigma{};
};

// Measures mirror k's pose from an image of the unit (spec.ImageCamera()'s size). Throws hovs::Error("label", ...)
// naming what is missing: too few markers (a covered label), a failed or inconsistent pose.
LabelMeasurement MeasureLabel(const TurretImage& image, const TurretSpec& spec, int k, const LabelOptions& options);

// The label's measurement precision for mirror k at the machine's image resolution: the median sigma (as
// LabelMeasurement::sigma) of `images` renders of the mirror at its nominal pose, the label in focus.
std::array<double, 5> LabelPrecision(const TurretSpec& spec, int k, const LabelOptions& options, int images = 3);

}  // namespace hovs::rig
