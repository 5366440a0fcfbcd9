// One monocular calibration as hovs calibrate runs it, callable from any driver (the command, hovs validate, a
// Monte-Carlo study, a Slurm shard, Python): the polynomial model at every degree of the order-selection table
// (the article's Tables 1-2), the unified model and optionally the physical model and OpenCV omnidir on the
// corners the polynomial solve kept, and, for a synthetic dataset, every model against the exact rig.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "calib/board_suggestion.h"
#include "calib/checkerboard_detector.h"
#include "calib/evaluation.h"
#include "calib/omnidir_reference.h"
#include "calib/physical_calibration.h"
#include "calib/cross_validation.h"
#include "calib/polynomial_calibration.h"
#include "core/catadioptric.h"

namespace hovs::calib {

// The detector's outcome on one image (every image gets one: none is dropped silently).
struct ImageDetection {
  std::string image, status, corner_refinement;
  bool found = false, complete = false;
  int corners = 0, from_edges = 0, candidates = 0;
  int rejected = 0;  // corners removed by the detector's label check, and why
  std::string rejected_reason;
  double worst_label_error = 0;            // of the kept corners, in squares
  std::optional<CornerAccuracy> to_truth;  // with the exact corners of a synthetic image
};

// What a calibration starts from: corners per image and the image size; for a synthetic dataset the exact rig;
// in the detection modes the detector's record and the image files (for the rim and the figures).
struct CalibrationInput {
  std::vector<BoardObservation> observations;
  int width = 0, height = 0;
  std::optional<CatadioptricCamera<double>> truth;
  nlohmann::json description;                // where the corners came from, recorded in the output
  std::vector<ImageDetection> detection;     // detection modes only
  std::vector<std::filesystem::path> paths;  // the image file of each observation (detection modes)
};

// An image file as 8-bit grey (RGB converted as OpenCV does).
cv::Mat ReadGreyImage(const std::filesystem::path& path);

// Runs the detector on one image file and appends its record to `input` (and its observation, when found).
// With `truth` (the exact pixels of the board's visible corners), the detected corners are compared with them.
// The first image fixes the size; a later one of another size is an error naming the file.
void DetectInto(const std::filesystem::path& path, const std::string& name, const CheckerboardDetectOptions& options,
                const std::vector<Vec2d>* truth, CalibrationInput* input);

// A corner table (calib/polynomial_calibration.h, LoadCornerCsv) of images of the given size; every corner must
// lie in the image.
CalibrationInput CornerTableInput(const std::filesystem::path& table, int width, int height);

// Every image of a folder through the detector.
CalibrationInput ImageFolderInput(const std::filesystem::path& folder, const CheckerboardDetectOptions& options);

// Checks that at least three images have a usable board; returns the images without one as "name: status; ...".
std::string CheckDetections(const CalibrationInput& input, const std::string& where);

// "COLSxROWSxSQUARE" (inner corners, square in metres), e.g. 7x6x0.03. Throws naming `where`.
CheckerboardSpec ParseBoardSpec(const std::string& text, const std::string& where);

struct MonoCalibrationOptions {
  std::vector<int> degrees = {2, 3, 4, 5, 6};  // the order-selection table
  PolynomialCalibrationOptions polynomial;     // its degree is the reported model's
  bool omnidir = false;                        // also OpenCV omnidir on the same corners
  // The physical model, from this design (mirror, camera, occluder; aligned) when set.
  std::optional<CatadioptricCamera<double>> physical_nominal;
  PhysicalCalibrationOptions physical;
  bool rim = true;         // fit the rim of the mirror image in every image (with paths)
  int cross_validate = 0;  // K >= 2: K-fold cross-validation of the polynomial model (calib/cross_validation.h)
  // Projection uncertainty maps of the polynomial and unified models (calib/projection_uncertainty.h) at this
  // range (m; 0: infinity), over the calibrated annulus.
  bool uncertainty = true;
  double uncertainty_range_m = 0;
  int suggest = 0;  // > 0: this many next board poses that would lower the polynomial model's uncertainty most
};

struct OrderRow {
  int degree = 0;
  double rms_px = 0, mean_px = 0;
  bool converged = false;
  std::vector<double> per_image_mean_px;
};

struct MonoCalibration {
  std::vector<OrderRow> orders;
  PolynomialCalibration polynomial;       // the reported degree
  std::vector<BoardObservation> inliers;  // the corners it kept
  UnifiedCalibration unified;
  std::optional<PhysicalCalibration> physical;
  size_t rim_points = 0;
  std::optional<OmnidirResult> omnidir;
  std::optional<RayAccuracy> polynomial_vs_truth;
  std::optional<PhysicalAccuracy> physical_vs_truth;
  std::optional<CrossValidation> cross_validation;
  std::optional<UncertaintyMap> polynomial_uncertainty, unified_uncertainty;  // when the covariance is computable
  std::optional<Suggestions> suggestions;
};

// Runs every stage. `warn` receives what a user should know but that does not stop the calibration (an image
// whose rim was not found). Throws hovs::Error for an input no model can be fitted to.
MonoCalibration CalibrateMono(const CalibrationInput& input, const MonoCalibrationOptions& options,
                              const std::function<void(const std::string&)>& warn = {});

// The record written as calibration.json (without "tool" and "versions", which the caller adds).
nlohmann::json MonoCalibrationJson(const CalibrationInput& input, const MonoCalibrationOptions& options,
                                   const MonoCalibration& result);

// The text summary printed by hovs calibrate and written as summary.txt.
std::string MonoCalibrationSummary(const CalibrationInput& input, const MonoCalibration& result);

// The annulus of unified.yaml: the radii the kept corners cover around the unified model's centre, widened.
void CornerAnnulus(const MonoCalibration& result, double* min_radius, double* max_radius);

// Writes the report folder's files: calibration.json (`record`), calib_results.txt (OCamCalib), unified.yaml
// (OpenCV omnidir), summary.txt, figures/ and index.html (tables and figures; the JSON behind a link).
void WriteMonoCalibrationReport(const std::filesystem::path& folder, const CalibrationInput& input,
                                const MonoCalibration& result, const nlohmann::json& record);

}  // namespace hovs::calib
