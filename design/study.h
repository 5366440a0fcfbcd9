// A complete design study (sweep, optima, the marked design, radial resolution) and its report folder.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "design/config.h"
#include "design/design.h"

namespace hovs::design {

struct DesignStudy {
  SweepResult sweep;
  Optimum continuous;
  std::optional<Optimum> integer_mm;
  std::optional<Optimum> marked;  // the config's marked design, evaluated
  std::vector<ResolutionSample> resolution_continuous, resolution_marked;
  std::map<std::string, double> seconds;  // wall time per step
};

DesignStudy RunDesignStudy(const DesignConfig& config);

// Writes out_dir/ atomically: config.yaml, sweep.csv, design.json, radial_resolution.csv, figures/*.png,
// index.html, summary.txt. Nothing is left behind if anything fails. Returns the summary text.
std::string WriteDesignReport(const DesignConfig& config, const DesignStudy& study,
                              const std::filesystem::path& out_dir);

// Versions of every library the design layer uses.
std::map<std::string, std::string> DesignVersions();

}  // namespace hovs::design
