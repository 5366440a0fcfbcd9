// The difference between two models of one camera, as a map over the image (mrcal's model diff): every pixel of
// a grid is unprojected by model A, the bearing turned by the rotation that best maps A's frame onto B's over
// their common domain (two calibrations of one camera agree on its rays up to such a rotation, which the board
// poses absorb), and projected by model B. Per pixel: the distance to where it started (px) and the angle to B's
// own bearing of the pixel (degrees). Any pair of models (exact, polynomial, unified; of one or two files).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "core/statistics.h"

namespace hovs::calib {

struct ModelDiffOptions {
  int grid_step_px = 0;      // 0: about 120 grid columns across the image
  bool fit_rotation = true;  // false: the two mirror frames are taken as the same
  void Check(const std::string& where) const;
};

// A grid of pixels over an image: column i at u = i step, row j at v = j step.
struct ImageGrid {
  int width = 0, height = 0, step_px = 1, nx = 0, ny = 0;
  // A step of about width / 120 when `step_px` is 0.
  static ImageGrid Over(int width, int height, int step_px);
};

struct ModelDiff : ImageGrid {
  std::vector<double> px, deg;  // ny rows of nx values (row j at v = j step); NaN outside the common domain
  Mat3<double> b_from_a = Mat3<double>::Identity();
  double rotation_deg = 0;  // the angle of b_from_a
  SampleSummary px_stats, deg_stats;
  size_t common_pixels = 0;  // grid pixels in both domains
};

// Throws hovs::Error when the models' image sizes differ or their domains share fewer than 100 grid pixels.
ModelDiff DiffModels(const AnyModel& a, const AnyModel& b, const ModelDiffOptions& options = {});

// A per-pixel combination of several diffs of the same grid (e.g. the folds of a cross-validation): the RMS over
// the diffs where every one is defined. Throws if the grids differ.
ModelDiff RmsOfDiffs(const std::vector<ModelDiff>& diffs);

nlohmann::json ModelDiffJson(const ModelDiff& diff);

// Two maps (px and degrees) of the diff over the image, under `title`; the pixels outside the common domain grey.
// Drawn with OpenCV (no display needed).
void WriteModelDiffFigures(const ModelDiff& diff, const std::string& title, const std::filesystem::path& px_png,
                           const std::filesystem::path& deg_png);

// One map of `values` (ny rows of nx) over the grid's image: turbo colours from 0 to the 99th percentile, NaN
// cells pale grey (explained by `grey_note`), the title with the median, 95th percentile and maximum of `stats`.
void WriteGridMap(const ImageGrid& grid, const std::vector<double>& values, const std::string& title,
                  const SampleSummary& stats, const char* format, const std::string& grey_note,
                  const std::filesystem::path& png);

}  // namespace hovs::calib
