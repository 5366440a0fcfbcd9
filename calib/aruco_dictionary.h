// ArUco dictionaries by name (OpenCV's predefined ones): one table for the boards the renderer draws and the
// markers the stereo calibration detects.
#pragma once

#include <string>

namespace hovs::calib {

// OpenCV's cv::aruco::PREDEFINED_DICTIONARY_NAME value, or -1 for an unknown name.
int ArucoDictionaryId(const std::string& name);
// The known names, comma separated (for error messages).
std::string ArucoDictionaryNames();

}  // namespace hovs::calib
