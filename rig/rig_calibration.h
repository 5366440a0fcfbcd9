// The rig folder of the variable-scale unit: every mirror calibrated where the positioning loop puts it, with its
// mapping file, so that a switch loads calibrations that hold; and the check that they do: a freshly rendered board
// after a switch, its corners detected and reprojected through the stored model (the board's pose fitted, the
// model held fixed).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "rig/rig_study.h"

namespace hovs::rig {

struct RigCalibrationOptions {
  int frames = 9;                  // calibration boards per mirror (the article's 9)
  uint64_t seed = 1;               // the machine's seats (as rig switch --seed) and the board poses
  std::string layout = "article";  // the mapping file's views
  std::vector<int> mirrors;        // indices; empty: every mirror
  void Check(const std::string& where) const;
};

struct MirrorCalibration {
  std::string mirror;
  MirrorPose pose;    // the true pose the mirror was calibrated at (after alignment)
  double focus = 0;   // the lens focus it was calibrated at
  double rms_px = 0;  // the polynomial model's reprojection RMS on its boards
  int boards = 0;
};

// For every mirror (or options.mirrors): align it (its seat from options.seed), focus, render a calibration set there,
// calibrate (hovs calibrate's stages: polynomial and unified models), build the layout's mapping file; writes
// out/<id>/dataset, out/<id>/calibration, out/<id>/views.hmap and out/rig.json atomically. `versions` go into every
// output.
std::vector<MirrorCalibration> CalibrateRig(const TurretSpec& spec, const RigCalibrationOptions& options,
                                            const std::filesystem::path& out,
                                            const std::map<std::string, std::string>& versions);

struct FreshBoardCheck {
  double rms_px = 0;
  int corners = 0;
  std::string status;  // the detector's
};
// Renders one new board (seed) for mirror k at `pose` with the lens at `focus` and measures `model`'s
// reprojection RMS on it. Throws hovs::Error when no board is found.
FreshBoardCheck CheckOnFreshBoard(const TurretSpec& spec, int k, const MirrorPose& pose, double focus,
                                  const AnyModel& model, uint64_t seed);

}  // namespace hovs::rig
