// Cross-validation of the polynomial calibration: the images are dealt into K folds (image i into fold i mod K);
// for each fold the model is calibrated on the other folds and
//   - its held-out error measured on the fold's images: each board's pose fitted with the model held fixed
//     (calib/board_pose.h), then the RMS reprojection error of its corners;
//   - its difference from the model of all images mapped over the image (calib/model_diff.h).
// The spread map is the per-pixel RMS of those differences: where it is large, the calibration depends on which
// images it was given. K = the number of images is leave-one-image-out.
#pragma once

#include <string>
#include <vector>

#include "calib/model_diff.h"
#include "calib/polynomial_calibration.h"

namespace hovs::calib {

struct CrossValidationFold {
  std::vector<std::string> held_out;       // image names
  std::vector<double> held_out_image_rms;  // px, per held-out image (NaN: no pose)
  double train_rms = 0, held_out_rms = 0;  // px, over the corners
  ModelDiff diff_to_full;
};

struct CrossValidation {
  int folds = 0;
  std::vector<CrossValidationFold> fold;
  double held_out_rms = 0;  // px, over every held-out corner of every fold
  double train_rms = 0;     // px, the folds' own fits, over their corners
  ModelDiff spread;         // per-pixel RMS of the folds' differences from the full model
};

// Throws hovs::Error for folds < 2, or folds that leave fewer than three images to calibrate on.
CrossValidation CrossValidatePolynomial(const std::vector<BoardObservation>& observations, int width, int height,
                                        const PolynomialCalibrationOptions& options, int folds,
                                        const PolynomialModel<double>& full_model);

nlohmann::json CrossValidationJson(const CrossValidation& cv);

}  // namespace hovs::calib
