// The unified (Mei) model as an OpenCV FileStorage YAML file in the parameter names of OpenCV's omnidir
// (opencv_contrib ccalib; the names its omni_calibration sample writes): camera_matrix (3 x 3, skew in (0, 1)),
// distortion_coefficients (1 x 4: k1, k2, p1, p2), xi (1 x 1), image_width, image_height. cv::FileStorage
// reads it back directly, and cv::omnidir::projectPoints / undistortImage take K, D and xi as they are.
//
// Frames: omnidir's camera frame is (x, y, -z) of hovs' mirror frame (unified.h); the intrinsics are the same
// numbers. hovs adds optional keys: rms_px, annulus_px (valid radius range around (cx, cy)), and the standard
// deviations (stddev_xi, stddev_fx, ...); omnidir ignores them.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include "core/unified.h"

namespace hovs::calib {

struct OmnidirFile {
  UnifiedModel<double> model;
  double annulus_min = 0, annulus_max = 0;  // px; max 0: not given
  double rms_px = -1;                       // -1: not given
  std::map<std::string, double> stddev;
};

std::string FormatOmnidirYaml(const OmnidirFile& file);
// Throws hovs::Error naming the file and key: not a FileStorage file, missing or malformed keys, non-positive
// focal lengths or image size, a negative xi.
OmnidirFile ParseOmnidirYaml(const std::string& text, const std::string& source);
OmnidirFile LoadOmnidirYaml(const std::filesystem::path& path);
// True when the text is an OpenCV FileStorage YAML file (its "%YAML:1.0" header) with a camera_matrix.
bool LooksLikeOmnidirYaml(const std::string& text);

}  // namespace hovs::calib
