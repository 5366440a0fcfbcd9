// The design-study configuration: a YAML file, validated on load (unknown keys, wrong types, bad values are
// errors naming the file and the key). Lengths in metres, angles in degrees where the key says _deg.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "design/design.h"

namespace hovs::design {

// One mirror of a turret family: the design that is optimal for its objective under the shared constraints.
struct FamilyMember {
  std::string name;     // e.g. "reference", "long-range"
  Objective objective;  // what this mirror is for
  std::string purpose;  // one line for the report
};

struct DesignConfig {
  std::string name = "design";
  DesignProblem problem;
  SweepSpec sweep;
  bool integer_mm = true;
  std::optional<DesignPoint> marked;  // a design to mark on the figures (e.g. the article's a = 48, b = 44)
  int resolution_samples = 200;
  std::vector<FamilyMember> family;  // non-empty: a turret family study instead of one design
  std::string source;                // the file it came from
  std::string text;                  // its text, echoed into reports
};

DesignConfig ParseDesignConfig(const std::string& yaml_text, const std::string& source);
DesignConfig LoadDesignConfig(const std::filesystem::path& path);

}  // namespace hovs::design
