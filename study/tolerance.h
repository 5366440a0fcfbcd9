// Tolerance analysis of a design: Monte-Carlo over manufacturing and assembly errors, each sample evaluated with
// the core's exact model of the erroneous unit against the nominal model a user would run uncalibrated.
//
// Frames and conventions. The camera holds the unit: every error is expressed in the camera's frame, where the
// nominal mirror frame is the aligned one (F1 at 2c along the optical axis). An erroneous unit has its own mirror
// (a, b, rim diameter) resting by its rim on the plate at the nominal plate height above the pinhole (so a mirror
// of other a, b or rim has its second focus off the pinhole by its change of z_rim + 2c), the pinhole further
// moved by the lateral offset (x, y) and the height error (z), the camera turned about its centre by the tilt
// (about x and y), and its focal length and principal point off. Pixels are where the erroneous unit images a
// point; the nominal model reads them.
//
// Figures per sample (each the worst over its grid):
//   ray_error_deg        angle between the nominal bearing of a pixel and the erroneous unit's reflected ray,
//                        both in the camera frame, over 12 radii x 36 azimuths of the nominal image annulus
//   svp_deviation_mm     the erroneous unit's rays of the same pixels: their largest distance from the point
//                        nearest all of them (0 for a single-viewpoint unit; the caustic's extent)
//   view_error_px        the article's six perspective views (unwrap's `article` preset for the design) built
//                        from the nominal model: a point at view_range m seen through a view pixel lands, via the
//                        erroneous unit's image and the nominal model, this far from that pixel (9 x 5 per view)
//   depth_error_percent  two units of the design side by side (baseline along x, each with its own errors):
//                        points at the depth ranges, azimuths 45..315 degrees from the baseline and elevations
//                        -10 and -25 degrees, triangulated from the nominal models (depth/stereo.h): |range
//                        error| / range
// Samples are drawn per index from the seed, so any shard of the set computes the same samples as one process,
// and the report computed from the merged samples is the one process's, byte for byte.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/catadioptric.h"
#include "design/config.h"

namespace hovs::study {

enum class Distribution { kNormal, kUniform };

// One error source: a normal distribution of standard deviation `size` or a uniform one of half-width `size`,
// in the parameter's unit (Parameters()), drawn independently per component (x and y of a tilt).
struct Tolerance {
  Distribution distribution = Distribution::kNormal;
  double size = 0;
};

struct Parameter {
  std::string name, unit, meaning;
  int components = 1;
};
// mirror_a, mirror_b, rim_diameter (mm), mirror_tilt (deg, x and y), lateral_offset (mm, x and y), height (mm),
// focal_length (% of f), principal_point (px, u and v).
const std::vector<Parameter>& Parameters();

struct Metric {
  std::string name, unit, meaning;
};
const std::vector<Metric>& Metrics();  // ray_error_deg, svp_deviation_mm, view_error_px, depth_error_percent

struct ToleranceConfig {
  std::string name = "tolerance";
  std::string source, text;  // the file and its text, echoed into the report
  design::DesignConfig design;
  design::DesignPoint nominal;                  // the design config's marked design
  std::map<std::string, Tolerance> tolerances;  // by Parameters() name; absent: no error
  uint64_t seed = 1;
  double view_range = 5.0;                        // m
  std::vector<double> depth_ranges = {2, 5, 10};  // m
  double baseline = 0.64;                         // m
  std::map<std::string, double> limits;           // by Metrics() name: the user's limits
  void Check(const std::string& where) const;
};

// The YAML (study/reference.yaml documents every key); `design` is a design config, relative to the file.
// `design_override`: the design config to use instead of the file's (hovs tolerance --design; a merge rebuilds
// the config from the texts the study recorded).
ToleranceConfig ParseToleranceConfig(const std::string& yaml_text, const std::string& source,
                                     const std::filesystem::path& base_dir,
                                     const design::DesignConfig* design_override = nullptr);
ToleranceConfig LoadToleranceConfig(const std::filesystem::path& path,
                                    const design::DesignConfig* design_override = nullptr);

// One unit's errors in SI units: a, b, rim diameter (m), tilt (rad, about x and y), offset (m: x, y lateral, z
// height), focal length (relative), principal point (px).
struct UnitErrors {
  double a = 0, b = 0, rim = 0;
  Vec2d tilt = Vec2d::Zero();
  Vec3d offset = Vec3d::Zero();
  double focal = 0;
  Vec2d principal_point = Vec2d::Zero();
  UnitErrors Scaled(double k) const;
};

// Parameter p's errors alone at magnitude `size` (its unit) along its first component.
UnitErrors SingleError(const std::string& parameter, double size);

// The erroneous unit of a design.
CatadioptricCamera<double> ErroneousRig(const design::DesignPoint& p, const design::CameraSpec& camera,
                                        const UnitErrors& e);

// Sample `index`'s errors of unit `unit` (0 or 1): seeded by (seed, index, unit) alone.
UnitErrors DrawErrors(const ToleranceConfig& config, int64_t index, int unit);

// A sample's figures in Metrics() order. NaN: the figure failed, because the erroneous unit could evaluate less
// than 90 % of the figure's grid (its mirror no longer covers the pixels, the points leave its image, the rig does
// not triangulate). A failed figure is counted as failed, never as a small error: it ranks above every value.
struct SampleFigures {
  double values[4] = {0, 0, 0, 0};
  bool Failed(int m) const { return !(values[m] == values[m]); }
};

// The nominal geometry and the grids, built once; Evaluate is thread-safe.
class ToleranceEvaluator {
 public:
  explicit ToleranceEvaluator(const ToleranceConfig& config);
  ~ToleranceEvaluator();
  SampleFigures Evaluate(const UnitErrors& left, const UnitErrors& right) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct Sample {
  int64_t index = 0;
  UnitErrors left, right;
  SampleFigures figures;
};

// Samples [count * shard / shards, count * (shard + 1) / shards), in parallel, in index order; `progress`: a
// progress line on stderr for long runs.
std::vector<Sample> RunSamples(const ToleranceConfig& config, int64_t count, int shard_index, int shard_count,
                               bool progress = false);

// The study's report (tolerance.json's "report"): percentiles and histograms of each figure, the sensitivity of
// each figure to each parameter alone, and the tolerances that keep each figure under its limit.
nlohmann::json AnalyseSamples(const ToleranceConfig& config, const std::vector<Sample>& samples);

// Writes out/ (staged): tolerance.json, samples.csv and, for a whole study (not a shard), index.html and
// figures/ (histograms, where VTK can render). `shard_count` > 1: a shard, for MergeToleranceShards. Returns the
// study's warnings (figures a share of the samples could not evaluate), for the command to print.
std::vector<std::string> WriteToleranceStudy(const ToleranceConfig& config, int64_t count, int shard_index,
                                             int shard_count, const std::filesystem::path& out,
                                             const std::map<std::string, std::string>& versions, bool progress = false);
// Joins shard folders of one study into the folder one process writes; refuses shards of another config, seed,
// sample count or version, or a samples file that does not match its checksum, naming the shard. Returns the
// study's warnings.
std::vector<std::string> MergeToleranceShards(const std::vector<std::filesystem::path>& shards,
                                              const std::filesystem::path& out);
// True if the folder holds a tolerance study or shard (tolerance.json).
bool IsToleranceFolder(const std::filesystem::path& dir);

}  // namespace hovs::study
