// The unified (Mei) model as an OpenCV FileStorage file in the parameter names of OpenCV's omnidir (opencv_contrib
// ccalib) and of its omni_calibration sample: camera_matrix (3 x 3, skew in (0, 1)), distortion_coefficients
// (1 x 4: k1, k2, p1, p2), xi (a plain number, as the sample writes it: `double xi; fs["xi"] >> xi` reads it),
// image_width, image_height, and the board poses as the sample's extrinsic_parameters (one row per board: rvec,
// tvec) with nFrames. cv::FileStorage reads it back directly, and cv::omnidir::projectPoints / undistortImage take
// K, D and xi as they are.
//
// Read: hovs' YAML and the sample's own output, YAML or XML (the sample's default), whose other keys
// (calibration_time, flags, used_imgs, rms, image_points) are accepted; xi as a number or a 1 x 1 matrix (hovs
// wrote the matrix before). The sample writes no image size: the model then has width = height = 0 (unknown),
// and the caller supplies it (WithImageSize).
//
// Frames: omnidir's camera frame is (x, y, -z) of hovs' mirror frame (unified.h); the intrinsics are the same
// numbers. A board pose cam_from_board (mirror frame) is written as F R F, F t with F = diag(1, 1, -1) (the board's
// own z flipped too, which leaves its points, z = 0, where they are). hovs adds optional keys: rms_px, annulus_px
// (valid radius range around (cx, cy)), and the standard deviations (stddev_xi, stddev_fx, ...); omnidir ignores
// them.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/rigid.h"
#include "core/unified.h"

namespace hovs::calib {

struct OmnidirFile {
  UnifiedModel<double> model;
  double annulus_min = 0, annulus_max = 0;  // px; max 0: not given
  double rms_px = -1;                       // -1: not given
  std::map<std::string, double> stddev;
  std::vector<Rigid3d> cam_from_board;  // the boards' poses (hovs' mirror frame); empty: not given
};

std::string FormatOmnidirYaml(const OmnidirFile& file);
// Throws hovs::Error naming the file and key: not a FileStorage file, missing or malformed keys, non-positive
// focal lengths, an image size outside 1..65535 when given, a negative xi.
OmnidirFile ParseOmnidirYaml(const std::string& text, const std::string& source);
// The XML form the sample writes by default (read by hovs' own small reader, not cv::FileStorage; at most 64 MB).
OmnidirFile ParseOmnidirXml(const std::string& text, const std::string& source);
// Either form, by its first bytes.
OmnidirFile LoadOmnidirYaml(const std::filesystem::path& path);
// True when the text is an OpenCV FileStorage YAML file (its "%YAML:1.0" header) with a camera_matrix.
bool LooksLikeOmnidirYaml(const std::string& text);
// True when the text is an OpenCV FileStorage XML file (<opencv_storage>) with a camera_matrix.
bool LooksLikeOmnidirXml(const std::string& text);

// The model with its image size: the file's, or `width` x `height` when the file has none (both 0: none given).
// Throws naming `source` when neither gives one, or when both do and they differ.
UnifiedModel<double> WithImageSize(const OmnidirFile& file, int width, int height, const std::string& source);

}  // namespace hovs::calib
