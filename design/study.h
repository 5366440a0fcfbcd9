// A complete design study (sweep, optima, the marked design, radial resolution) and its report folder.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "design/config.h"
#include "design/design.h"
#include "design/optics_report.h"
#include "results/html.h"

namespace hovs::design {

struct DesignStudy {
  SweepResult sweep;
  Optimum continuous;
  std::optional<Optimum> integer_mm;
  std::optional<Optimum> marked;  // the config's marked design, evaluated
  std::vector<ResolutionSample> resolution_continuous, resolution_marked;
  std::vector<DesignOptics> optics;       // the chosen design (integer-mm optimum, else continuous) and the marked one
  std::map<std::string, double> seconds;  // wall time per step
};

DesignStudy RunDesignStudy(const DesignConfig& config);
// The study on a sweep already made (a merge of sweep shards): optima, the marked design, resolution.
DesignStudy RunDesignStudy(const DesignConfig& config, SweepResult sweep, double sweep_seconds);

// Shards of a design sweep (hovs design --shard I/N): rows [rows * I / N, rows * (I + 1) / N) of the grid, written
// to out/design-shard.json (the config, the shard, every value of its rows, exact); MergeDesignShards joins the
// shards' rows and writes the report one process writes (WriteDesignReport; design.json differs only in its
// "seconds"). Refuses a family config, and shards of another config or version, naming the shard.
void WriteDesignShard(const DesignConfig& config, int shard_index, int shard_count, const std::filesystem::path& out,
                      const std::map<std::string, std::string>& versions);
bool IsDesignShard(const std::filesystem::path& dir);
std::string MergeDesignShards(const std::vector<std::filesystem::path>& shards, const std::filesystem::path& out);

// One design evaluated against a problem: metrics, constraints, objective and violation (method says where the
// design came from).
Optimum EvaluateDesign(const DesignPoint& p, const DesignProblem& problem, const std::string& method);

// The JSON forms of design.json: a design's metrics and constraints, and the whole study (without versions).
nlohmann::json MetricsJson(const Metrics& m);
nlohmann::json ProblemJson(const DesignConfig& config);
nlohmann::json OptimumJson(const Optimum& o);
nlohmann::json DesignStudyJson(const DesignConfig& config, const DesignStudy& study);

// Writes out_dir/ atomically: config.yaml, sweep.csv, design.json, radial_resolution.csv, blur.csv, figures/*.png,
// index.html, summary.txt. Nothing is left behind if anything fails. Returns the summary text.
std::string WriteDesignReport(const DesignConfig& config, const DesignStudy& study,
                              const std::filesystem::path& out_dir);

// A report page's closing sections: the config's text and the libraries' versions.
void AppendConfigAndVersions(results::HtmlPage* page, const std::string& config_text,
                             const std::map<std::string, std::string>& versions);

// The objective in its natural sign and unit (2c in mm, field in deg, ...) and that unit's label.
double ObjectiveDisplay(Objective o, double value);
std::string ObjectiveLabel(Objective o);

// Versions of every library the design layer uses.
std::map<std::string, std::string> DesignVersions();

}  // namespace hovs::design
