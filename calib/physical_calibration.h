// Calibration of the physical model, beyond the usual central models: the hyperboloid's a and b, the camera's
// intrinsics (and optionally its radial-tangential distortion) and the camera's pose relative to the mirror
// (tilt and offset from the second focus), with every board pose, through the core's general
// (law-of-reflection) projection. Started from a nominal design and a polynomial calibration's poses.
#pragma once

#include <string>
#include <vector>

#include "calib/polynomial_calibration.h"
#include "core/catadioptric.h"

namespace hovs::calib {

struct PhysicalCalibrationOptions {
  // A camera turned about its pinhole resembles a camera with a shifted principal point: on exact corners all
  // parameters are recovered, but with corner noise the tilt trades off against cx, cy. Hold the intrinsics
  // fixed when they are known (the camera calibrated without the mirror) to measure the tilt.
  bool estimate_intrinsics = true;
  bool estimate_distortion = false;
  bool estimate_mirror = true;  // a and b; their common scale is weakly observable (only off the focus)
  int max_iterations = 200;
  // Points on the rim of the mirror image (calib/rim_positioning.h, DetectRimEdge), seen directly by the camera:
  // each adds a residual (px) for its camera ray missing the rim circle. The rim fixes the camera's height and
  // lateral place, which the boards' corners (seen through the mirror) constrain only weakly.
  std::vector<Vec2d> rim_points;
};

struct PhysicalCalibration {
  CatadioptricCamera<double> rig;
  Vec3d tilt = Vec3d::Zero();    // axis-angle, radians; the component about z is held at 0 (mirror symmetry)
  Vec3d offset = Vec3d::Zero();  // camera centre minus F2, mirror frame, m
  std::vector<Rigid3d> mirror_from_board;
  double rms = 0;
  double rim_rms = 0;  // px, over rim_points (0 without)
  bool converged = false;
  std::string solver_report;
};

// nominal: the design (mirror, camera, occluder) to start from; start: a calibration whose poses (mirror frame)
// seed the board poses.
PhysicalCalibration CalibratePhysical(const std::vector<BoardObservation>& observations,
                                      const CatadioptricCamera<double>& nominal, const PolynomialCalibration& start,
                                      const PhysicalCalibrationOptions& options = {});

}  // namespace hovs::calib
