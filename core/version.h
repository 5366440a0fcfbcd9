// Versions of hovs and of the libraries it was built with, recorded in every output.
#pragma once

#include <map>
#include <string>

namespace hovs {

// hovs' version and git description at configure time.
std::string HovsVersion();
// Library name -> version, for core's own dependencies (compiler, Eigen, Ceres). Higher layers add theirs.
std::map<std::string, std::string> CoreVersions();

}  // namespace hovs
