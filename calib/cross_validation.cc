#include "calib/cross_validation.h"

#include <cmath>

#include "calib/board_pose.h"
#include "core/error.h"

namespace hovs::calib {

CrossValidation CrossValidatePolynomial(const std::vector<BoardObservation>& obs, int width, int height,
                                        const PolynomialCalibrationOptions& options, int folds,
                                        const PolynomialModel<double>& full_model) {
  const int n = static_cast<int>(obs.size());
  HOVS_REQUIRE(folds >= 2, "--cross-validate", "needs at least 2 folds (got ", folds, ")");
  HOVS_REQUIRE(folds <= n, "--cross-validate", "more folds (", folds, ") than images (", n, ")");
  HOVS_REQUIRE(n - (n + folds - 1) / folds >= 3, "--cross-validate", folds, " folds of ", n,
               " images leave fewer than three images to calibrate each fold on");
  CrossValidation cv;
  cv.folds = folds;
  const AnyModel full = AnyModel::Polynomial(full_model, "the full calibration");
  double held_ss = 0, train_ss = 0;
  long held_n = 0, train_n = 0;
  std::vector<ModelDiff> diffs;
  for (int k = 0; k < folds; ++k) {
    std::vector<BoardObservation> train, test;
    for (int i = 0; i < n; ++i) (i % folds == k ? test : train).push_back(obs[i]);
    CrossValidationFold f;
    const PolynomialCalibration cal = CalibratePolynomial(train, width, height, options);
    const AnyModel model = AnyModel::Polynomial(cal.model, "fold " + std::to_string(k));
    long corners = 0;
    for (const auto& o : train) corners += static_cast<long>(o.pixels.size());
    f.train_rms = cal.rms, train_ss += cal.rms * cal.rms * corners, train_n += corners;
    double ss = 0;
    long m = 0;
    for (const auto& o : test) {
      f.held_out.push_back(o.image);
      Rigid3d pose;
      double rms = NAN;
      // The same physical board: the fold's estimate of its flex applies to the held-out images too.
      const std::vector<Vec3d> board = cal.board_extent.Warped(o.board_points, cal.board_warp);
      if (!FitBoardPose(model, board, o.pixels, &pose, &rms) || !std::isfinite(rms)) {
        f.held_out_image_rms.push_back(NAN);
        continue;
      }
      f.held_out_image_rms.push_back(rms);
      ss += rms * rms * o.pixels.size(), m += static_cast<long>(o.pixels.size());
    }
    f.held_out_rms = m ? std::sqrt(ss / m) : NAN;
    held_ss += ss, held_n += m;
    f.diff_to_full = DiffModels(model, full);
    diffs.push_back(f.diff_to_full);
    cv.fold.push_back(std::move(f));
  }
  HOVS_REQUIRE(held_n > 0, "--cross-validate", "no held-out board could be posed with its fold's model");
  cv.held_out_rms = std::sqrt(held_ss / held_n);
  cv.train_rms = std::sqrt(train_ss / train_n);
  cv.spread = RmsOfDiffs(diffs);
  return cv;
}

nlohmann::json CrossValidationJson(const CrossValidation& cv) {
  nlohmann::json folds = nlohmann::json::array();
  for (const auto& f : cv.fold) {
    nlohmann::json per = nlohmann::json::array();
    for (size_t i = 0; i < f.held_out.size(); ++i) {
      const double r = f.held_out_image_rms[i];
      per.push_back({{"image", f.held_out[i]}, {"rms_px", std::isfinite(r) ? nlohmann::json(r) : nlohmann::json()}});
    }
    folds.push_back({{"held_out", per},
                     {"train_rms_px", f.train_rms},
                     {"held_out_rms_px", f.held_out_rms},
                     {"diff_to_full", ModelDiffJson(f.diff_to_full)}});
  }
  return {{"folds", cv.folds},
          {"assignment", "image i in fold i mod K"},
          {"held_out_rms_px", cv.held_out_rms},
          {"train_rms_px", cv.train_rms},
          {"spread", ModelDiffJson(cv.spread)},
          {"per_fold", folds}};
}

}  // namespace hovs::calib
