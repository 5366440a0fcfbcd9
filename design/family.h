// The turret's mirror family (the article's variable-scale unit, section 3.1 item 2): for one camera and lens,
// one mirror per objective, every one under the same constraints and within the push rod's travel.
//
// Each member is the constrained optimum of its objective (NLopt from the best point of a sweep, as for one
// design); the mirror the turret carries is the integer-millimetre optimum when the config asks for it (the
// article's 48 / 44 is the integer-millimetre smallest system), else the continuous one. The rod position of a
// mirror is its plate height, z_rim + 2c: where the mounting plate (the rim plane) sits above the camera's pinhole
// when the pinhole is at the mirror's second focus.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "design/config.h"
#include "design/optics_report.h"
#include "design/design.h"

namespace hovs::design {

struct FamilyMirror {
  FamilyMember member;
  DesignProblem problem;  // the shared problem with this member's objective
  Optimum continuous;
  std::optional<Optimum> integer_mm;
  std::vector<ResolutionSample> resolution;  // of the chosen design
  std::optional<DesignOptics> optics;        // of the chosen design: focus, blur, depth of field
  const Optimum& Chosen() const { return integer_mm ? *integer_mm : continuous; }
};

struct MirrorFamily {
  std::vector<FamilyMirror> mirrors;
  std::map<std::string, double> seconds;
  // Pairs of members whose chosen designs coincide (same a, b, d to 0.1 mm): a family that offers fewer scales.
  std::vector<std::pair<std::string, std::string>> coincident;
};

// Runs every member of config.family. Throws hovs::Error naming the member when an objective has no feasible
// design (for example a rod travel that excludes every mirror).
MirrorFamily RunFamilyStudy(const DesignConfig& config);

nlohmann::json FamilyJson(const DesignConfig& config, const MirrorFamily& family);

// Writes out_dir/ atomically: config.yaml, family.json, family.csv (the table), radial_resolution.csv,
// figures/family_resolution.png (every member's curve on one plot), figures/rod_positions.png, index.html and
// summary.txt. Returns the summary text.
std::string WriteFamilyReport(const DesignConfig& config, const MirrorFamily& family,
                              const std::filesystem::path& out_dir);

}  // namespace hovs::design
