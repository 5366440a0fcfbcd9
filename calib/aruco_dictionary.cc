#include "calib/aruco_dictionary.h"

#include <map>
#include <opencv2/aruco.hpp>

#include "core/error.h"

namespace hovs::calib {
namespace {
const std::map<std::string, int>& Table() {
  static const std::map<std::string, int> ids = {{"DICT_4X4_50", cv::aruco::DICT_4X4_50},
                                                 {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
                                                 {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
                                                 {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
                                                 {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
                                                 {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
                                                 {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL}};
  return ids;
}
}  // namespace

int ArucoDictionaryId(const std::string& name, const std::string& where) {
  const auto it = Table().find(name);
  HOVS_REQUIRE(it != Table().end(), where, "unknown ArUco dictionary '", name, "' (known: ", ArucoDictionaryNames(),
               ")");
  return it->second;
}

std::string ArucoDictionaryNames() {
  std::string s;
  for (const auto& [name, id] : Table()) s += (s.empty() ? "" : ", ") + name;
  return s;
}

}  // namespace hovs::calib
