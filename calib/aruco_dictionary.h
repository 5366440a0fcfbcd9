// ArUco dictionaries by name (OpenCV's predefined ones): one table for the boards the renderer draws and the
// markers the stereo calibration detects.
#pragma once

#include <string>

namespace hovs::calib {

// OpenCV's cv::aruco::PREDEFINED_DICTIONARY_NAME value of a name. Throws hovs::Error(where) naming the known ones
// for an unknown name: every reader of a dictionary name checks it here, before OpenCV is asked for it.
int ArucoDictionaryId(const std::string& name, const std::string& where);
// The known names, comma separated (for error messages).
std::string ArucoDictionaryNames();

}  // namespace hovs::calib
