// The corners of one unit of a dataset manifest as a calibration's input: detected in its images (compared with
// the exact corners when the dataset is synthetic), or the exact corners themselves with seeded noise (to check
// a solver alone). A synthetic unit also gives the exact rig and the design a physical calibration starts from.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "calib/mono_calibration.h"
#include "raytrace/scene.h"

namespace hovs::scenes {

struct DatasetCalibrationOptions {
  std::string unit;            // the unit's name in the manifest; empty: the first
  bool truth_corners = false;  // the exact corners instead of the detector's
  double corner_noise_px = 0;  // Gaussian, added to the exact corners
  uint64_t seed = 1;
  calib::CheckerboardDetectOptions detect;  // its board (square 0) is taken from the manifest when it has one
};

struct DatasetCalibrationInput {
  calib::CalibrationInput input;
  std::optional<raytrace::CatadioptricUnit> unit;  // synthetic datasets: the exact unit
};

DatasetCalibrationInput LoadDatasetCalibrationInput(const std::filesystem::path& manifest,
                                                    const DatasetCalibrationOptions& options);

// The design a physical calibration starts from: `unit` with its camera put back in place (no tilt, no offset).
raytrace::CatadioptricUnit AlignedDesign(raytrace::CatadioptricUnit unit);

}  // namespace hovs::scenes
