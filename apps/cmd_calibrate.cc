// hovs calibrate: monocular calibration from a corner table (e.g. shared/data/vmr), a dataset manifest
// (synthetic or real) or a folder of images. Corners come from hovs' checkerboard detector (every image gets a
// detection status; with ground truth, the detected corners are compared with the exact ones); with
// --truth-corners a synthetic manifest's exact corners are used instead (optionally with seeded noise) to check
// the solver alone. With a synthetic manifest the result is compared with the exact rig
// (calib/mono_calibration.h runs every stage).
#include <cstdio>
#include <iostream>

#include "apps/commands.h"
#include "calib/mono_calibration.h"
#include "core/error.h"
#include "core/io.h"
#include "scenes/calibration_input.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"

namespace hovs::apps {
namespace {

struct CalibrateCommandOptions {
  std::string corners, size, dataset, unit, images, board, out = "results/calibration", loss = "none";
  bool truth_corners = false, physical = false, physical_intrinsics = false, physical_mirror = false, rim = true;
  std::string nominal;
  int subpix = 0;
  std::string corner_refinement = "edges";
  std::vector<int> degrees = {2, 3, 4, 5, 6};
  int degree = 4;
  double loss_scale = 1.0, noise = 0.0, outlier_sigmas = 5.0;
  uint64_t seed = 1;
  bool omnidir = false;
  int cross_validate = 0;
  bool board_flex = false, board_flex_per_image = false, decentering = false;
  double uncertainty_range = 0;
  int suggest = 0;
};

int RunCalibrate(const CalibrateCommandOptions& o, const GlobalOptions& global) {
  HOVS_REQUIRE(int(!o.corners.empty()) + int(!o.dataset.empty()) + int(!o.images.empty()) == 1, "hovs calibrate",
               "give exactly one of --corners, --dataset and --images");
  HOVS_REQUIRE(o.noise == 0 || o.truth_corners, "--corner-noise",
               "adds noise to a synthetic manifest's exact corners: it needs --truth-corners");
  calib::CheckerboardDetectOptions detect;
  detect.subpix_half_window = o.subpix;
  detect.corner_refinement = o.corner_refinement;
  if (o.board.rfind("charuco:", 0) == 0)
    detect.charuco = calib::ParseCharucoSpec(o.board, "--board");
  else if (!o.board.empty())
    detect.board = calib::ParseBoardSpec(o.board, "--board");
  else
    detect.board.square = 0;  // from the manifest
  calib::CalibrationInput in;
  std::optional<raytrace::CatadioptricUnit> unit;  // a synthetic dataset's exact unit
  if (!o.corners.empty()) {
    int w = 0, h = 0;
    ParseImageSize(o.size, "--size", &w, &h);
    in = calib::CornerTableInput(o.corners, w, h);
  } else if (!o.dataset.empty()) {
    auto d = scenes::LoadDatasetCalibrationInput(o.dataset, {o.unit, o.truth_corners, o.noise, o.seed, detect});
    in = std::move(d.input), unit = std::move(d.unit);
  } else {
    HOVS_REQUIRE(!o.board.empty(), "--images", "a folder of images needs --board");
    in = calib::ImageFolderInput(o.images, detect);
  }
  const std::string input_name = !o.corners.empty() ? o.corners : !o.dataset.empty() ? o.dataset : o.images;
  if (!in.detection.empty()) {
    const std::string failed = calib::CheckDetections(in, input_name);
    if (!global.quiet && !failed.empty()) std::fprintf(stderr, "hovs calibrate: no board in %s\n", failed.c_str());
  }
  calib::MonoCalibrationOptions mo;
  mo.polynomial.degree = o.degree, mo.polynomial.loss = o.loss, mo.polynomial.loss_scale = o.loss_scale;
  mo.polynomial.outlier_sigmas = o.outlier_sigmas;
  mo.omnidir = o.omnidir;
  mo.cross_validate = o.cross_validate;
  mo.uncertainty_range_m = o.uncertainty_range;
  mo.suggest = o.suggest;
  mo.polynomial.board_flex = o.board_flex || o.board_flex_per_image;
  mo.polynomial.board_flex_per_image = o.board_flex_per_image;
  mo.polynomial.estimate_decentering = o.decentering;
  std::optional<raytrace::CatadioptricUnit> design;
  if (o.physical) {
    if (!o.nominal.empty()) {
      auto cfg = scenes::LoadSceneConfig(o.nominal);
      if (!o.unit.empty()) scenes::SelectUnit(&cfg, o.unit);
      design = scenes::AlignedDesign(cfg.description.units[0]);
    } else {
      HOVS_REQUIRE(unit.has_value(), "--physical", "give the unit's design with --nominal scene.yaml");
      design = scenes::AlignedDesign(*unit);  // the manifest's unit without its misalignment
    }
    mo.physical_nominal = design->rig;
    mo.physical.estimate_intrinsics = o.physical_intrinsics;
    mo.physical.estimate_mirror = o.physical_mirror;
    mo.rim = o.rim;
  }
  const auto warn = [&](const std::string& w) {
    if (!global.quiet) std::fprintf(stderr, "hovs calibrate: %s\n", w.c_str());
  };
  const calib::MonoCalibration result = OnInput(input_name, [&] { return calib::CalibrateMono(in, mo, warn); });
  nlohmann::json j = calib::MonoCalibrationJson(in, mo, result);
  j["tool"] = "hovs calibrate";
  j["versions"] = Versions();
  if (result.physical) {
    raytrace::CatadioptricUnit calibrated = *design;
    calibrated.rig = result.physical->rig;
    j["physical"]["unit"] = scenes::UnitToJson(calibrated);
  }
  StagedDirectory stage(o.out, "calibrate");
  calib::WriteMonoCalibrationReport(stage.staging(), in, result, j);
  stage.Commit();
  if (global.json)
    std::cout << j.dump(2) << "\n";
  else if (!global.quiet)
    std::cout << calib::MonoCalibrationSummary(in, result);
  return 0;
}

}  // namespace

Runner SetupCalibrate(CLI::App* sub, const GlobalOptions* global) {
  auto o = std::make_shared<CalibrateCommandOptions>();
  sub->add_option("--corners", o->corners, "corner table: image,corner,board_x_mm,board_y_mm,u_px,v_px");
  sub->add_option("--size", o->size, "image size WxH (with --corners)");
  sub->add_option("--dataset", o->dataset, "dataset manifest (dataset.json): corners detected in its images");
  sub->add_option("--images", o->images, "folder of images (png, jpg, tif, exr): corners detected");
  sub->add_option("--board", o->board,
                  "checkerboard COLSxROWSxSQUARE: inner corners and square (m), e.g. 7x6x0.03; or a ChArUco board "
                  "charuco:SXxSYxSQUARExMARKER[:DICTIONARY]: squares, square and marker sides (m), e.g. "
                  "charuco:8x6x0.03x0.022 (default dictionary DICT_4X4_250)");
  sub->add_flag("--physical", o->physical,
                "also calibrate the physical model: mirror a, b and the camera's tilt and offset, exact projection");
  sub->add_option("--nominal", o->nominal,
                  "--physical: scene YAML with the unit's design (default: the manifest's unit, aligned)");
  sub->add_flag("--physical-intrinsics", o->physical_intrinsics,
                "--physical: also estimate the camera intrinsics (default: held at the nominal camera's, i.e. a camera "
                "calibrated without its mirror)");
  sub->add_flag("--physical-mirror", o->physical_mirror,
                "--physical: also estimate the mirror's a and b (default: held at the design; their common scale is "
                "weakly observable and drifts with corner noise)");
  sub->add_flag("!--no-rim", o->rim,
                "--physical: do not fit the rim of the mirror image (by default it is found in every image and fixes "
                "the camera's height and lateral place)");
  sub->add_flag("--truth-corners", o->truth_corners, "use a synthetic manifest's exact corners instead of detecting");
  sub->add_option("--corner-refinement", o->corner_refinement,
                  "edges: corners where the board lines measured along their length cross (default); subpix: "
                  "cv::cornerSubPix alone")
      ->capture_default_str();
  AddBounded(sub, "--subpix-window", &o->subpix, "cornerSubPix half window, px (0: 0.35 x the local square)", 0, 100);
  sub->add_option("--unit", o->unit, "unit name in the manifest (default: the first)");
  AddBounded(sub, "--corner-noise", &o->noise, "Gaussian noise added to ground-truth corners, px", 0, 100);
  AddBounded(sub, "--seed", &o->seed, "seed of the corner noise", 0, 9007199254740992.0);
  AddBounded(sub, "--degree", &o->degree, "polynomial degree of the reported model", 2, 8);
  sub->add_option("--loss", o->loss, "none | huber | cauchy")->capture_default_str();
  AddBounded(sub, "--loss-scale", &o->loss_scale, "robust loss scale, px", 0, 1000, true);
  sub->add_flag("--compare-omnidir", o->omnidir, "also run OpenCV omnidir on the same corners");
  sub->add_flag("--board-flex", o->board_flex,
                "estimate the board's flex (two parabolas along its axes, shared by every image, as mrcal's) in the "
                "polynomial and unified solves");
  sub->add_flag("--board-flex-per-image", o->board_flex_per_image,
                "the board's flex estimated for each image (a board that bends differently each time it is held)");
  sub->add_flag("--decentering", o->decentering,
                "also estimate the polynomial model's decentering p1, p2 (a lens or camera off the mirror's axis; "
                "hovs' extension: no calib_results.txt is written)");
  AddBounded(sub, "--cross-validate", &o->cross_validate,
             "K-fold cross-validation (image i in fold i mod K; K = the image count: leave one out): held-out "
             "error and the map of the folds' model differences (0: off)",
             0, 10000);
  AddBounded(sub, "--uncertainty-range", &o->uncertainty_range,
             "range of the point whose projection uncertainty is mapped, m (0: infinity)", 0, 1e6);
  AddBounded(sub, "--suggest", &o->suggest,
             "propose this many next board poses that would lower the projection uncertainty most, drawn through "
             "the model (0: off)",
             0, 20);
  AddBounded(sub, "--outlier-sigmas", &o->outlier_sigmas,
             "reject corners above this many robust sigmas (at least 0.5 px) after the first solve; 0: keep all", 0,
             1000);
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  return [o, global]() { return RunCalibrate(*o, *global); };
}

}  // namespace hovs::apps
