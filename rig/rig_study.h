// Runs of the variable-scale unit in simulation and their reports: the alignment study (many seeded disturbed
// starts per mirror, with the faults one can inject), a switch from one mirror to another (rotate, rod, align,
// focus), and the rig folder that holds every mirror's calibration and mapping file (rig.json).
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/polynomial.h"
#include "rig/focus.h"
#include "rig/positioning.h"

namespace hovs::rig {

// Versions of the libraries a rig run uses (renderer, OpenCV, report).
std::map<std::string, std::string> RigVersions();

// A fault to inject: "AXIS:stuck", "AXIS:lost=F" (fraction of every move lost) or "label:covered".
struct FaultSpec {
  std::string axis;  // an axis name or "label"
  AxisFault fault;
  bool label_covered = false;
};
FaultSpec ParseFault(const std::string& text, const std::string& where);

struct StartSpec {
  double lateral = 2e-3, tilt = 1.5 * M_PI / 180, height = 3e-3;  // m, rad, m
  void Check(const std::string& where) const;
};

struct AlignRun {
  int mirror = 0;
  uint64_t seed = 0;
  MirrorPose start;
  AlignResult result;
  std::optional<FocusResult> focus;
  double render_seconds = 0, machine_seconds = 0;
};

struct AlignStudyOptions {
  std::vector<int> mirrors;  // indices into the spec
  int starts = 20;
  uint64_t seed = 1;
  StartSpec start;
  AlignOptions align;
  bool focus = false;
  FocusOptions focus_options;
  std::optional<FaultSpec> fault;
  void Check(const std::string& where, const TurretSpec& spec) const;
};

// Runs every mirror from `starts` seeded disturbed starts (seed, seed + 1, ...; each with its own seating errors).
std::vector<AlignRun> RunAlignStudy(const TurretSpec& spec, const AlignStudyOptions& options);

// Summary figures per mirror: medians and worst values of the final true deviations and the iterations.
struct AlignSummary {
  std::string mirror;
  int runs = 0, converged = 0;
  double median_lateral = 0, worst_lateral = 0, median_tilt = 0, worst_tilt = 0, median_height = 0,
         worst_height = 0;  // m, rad, m (absolute)
  double median_iterations = 0, worst_iterations = 0;
  double median_focus_ratio = 0;  // sharpness after the focus loop / the best the loop saw (with focus)
};
std::vector<AlignSummary> SummariseAlignStudy(const TurretSpec& spec, const std::vector<AlignRun>& runs);

nlohmann::json AlignRunJson(const TurretSpec& spec, const AlignRun& run);

// Writes out_dir/ atomically: align.json (every step of every run: truth, measurement, reported axes, commands,
// machine time), summary.txt, figures/convergence_{lateral,tilt,height}.png, index.html. Returns the summary.
std::string WriteAlignReport(const TurretSpec& spec, const AlignStudyOptions& options,
                             const std::vector<AlignRun>& runs, const std::filesystem::path& out_dir);

// The rig folder (hovs rig calibrate): rig.json {"format": "hovs-rig", "version": 2, "machine": {source, name,
// geometry_checksum}, "seed", "downscale", "mirrors": {"<id>": {"calibration", "calibration_checksum", "map",
// "map_checksum", "mirror": {a, b, rim_diameter}, ...}}}, paths relative to the folder.
inline constexpr int kRigFolderVersion = 2;
struct RigFolder {
  std::filesystem::path root;
  int downscale = 1;             // the image resolution its calibrations are for (1/downscale of the camera's)
  std::optional<uint64_t> seed;  // the machine's seats its calibrations were made on (hovs rig calibrate --seed)
  struct Entry {
    std::filesystem::path calibration, map;
    PolynomialModel<double> model;  // the calibration's, checked
  };
  std::map<std::string, Entry> mirrors;
};
// Reads rig.json and checks every file it names against the machine, the mirror and the camera it is for, so
// that a switch never loads another mirror's calibration, a map of another camera or size, or a folder made on
// another machine: the machine's geometry (MachineGeometryJson's checksum), each id a mirror of the machine with
// the recorded a, b and rim, each path inside the folder, each file's checksum, each calibration of the image
// size at the folder's resolution and imaging the field of its mirror (its elevation at the image's annulus within
// 0.5 deg of the machine's model of that mirror, which the other mirrors are not), each map built from its
// calibration for that size. Throws hovs::Error naming rig.json, the mirror and the file.
RigFolder LoadRigFolder(const std::filesystem::path& rig_json, const TurretSpec& spec);

// A switch in simulation: the unit starts on mirror `from`, aligned as its seat allows (the axes at that mirror's
// nominal positions), then the turret turns to `to`, the rod moves to its plate height, the lateral and tilt axes
// return to zero and the focus to the plate (the label sharp); then the loop aligns and the focus loop focuses
// the mirror image.
struct SwitchResult {
  int from = 0, to = 0;
  double move_seconds = 0;  // machine time of the turret and rod move
  MirrorPose after_move;    // truth after the move, before alignment
  AlignResult align;
  std::optional<FocusResult> focus;
  double machine_seconds = 0, render_seconds = 0;
  int images = 0;
};
SwitchResult SimulateSwitch(const TurretSpec& spec, int from, int to, uint64_t seed, const AlignOptions& align,
                            const FocusOptions& focus);
nlohmann::json SwitchJson(const TurretSpec& spec, const SwitchResult& s);

}  // namespace hovs::rig
