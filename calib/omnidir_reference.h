// OpenCV's omnidir (the unified model of Mei, opencv_contrib ccalib) run on the same corners, so reports can
// show hovs beside the tool users would otherwise pick. Its RMS is recomputed with hovs' definition:
// sqrt(mean squared 2-D reprojection distance) over the corners of the images omnidir kept.
#pragma once

#include <string>
#include <vector>

#include "calib/polynomial_calibration.h"

namespace hovs::calib {

struct OmnidirResult {
  bool ok = false;
  std::string error;
  double rms = 0;         // hovs' definition
  double opencv_rms = 0;  // the value cv::omnidir::calibrate returns
  int images_used = 0;
  double xi = 0, fx = 0, fy = 0, cx = 0, cy = 0, skew = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;
};

OmnidirResult RunOpenCvOmnidir(const std::vector<BoardObservation>& observations, int width, int height);

}  // namespace hovs::calib
