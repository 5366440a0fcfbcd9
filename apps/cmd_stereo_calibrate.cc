// hovs stereo-calibrate: the relative pose of two units from ArUco board pairs (a stereo_aruco dataset, synthetic
// or real). Models: the manifest's units (exact rigs), or --left-model / --right-model (calibrated models).
// depth/stereo_report.h lists what the report folder holds; it is replaced atomically.
#include <cstdio>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "core/error.h"
#include "core/io.h"
#include "depth/stereo_dataset.h"
#include "depth/stereo_report.h"

namespace hovs::apps {

Runner SetupStereoCalibrate(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string dataset, out = "results/stereo-calibration", left_model, right_model, model_kind = "auto";
    double huber = 1.0, marker_check_px = 2.0;
    std::string corner_refinement = "edges";
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--dataset", o->dataset, "stereo_aruco dataset manifest (two units per frame)")->required();
  sub->add_option("--left-model", o->left_model,
                  "calibrated model of the first unit (calib_results.txt or calibration.json)");
  sub->add_option("--model-kind", o->model_kind,
                  "with calibration.json models: auto (physical if present) | physical | polynomial | unified")
      ->capture_default_str();
  sub->add_option("--right-model", o->right_model, "calibrated model of the second unit");
  AddBounded(sub, "--huber", &o->huber, "robust loss scale, px", 0, 1000, true);
  AddBounded(sub, "--marker-check", &o->marker_check_px,
             "drop markers with a corner this far (px) from the board pose of the other corners; 0: keep all", 0, 1000);
  sub->add_option("--corner-refinement", o->corner_refinement,
                  "marker corners: edges (where the marker's two sides, measured along their length, meet) | "
                  "subpix (cornerSubPix only)")
      ->check(CLI::IsMember({"edges", "subpix"}))
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    const depth::StereoDataset dataset = depth::LoadStereoDataset(o->dataset);
    const AnyModel left = o->left_model.empty() ? AnyModel::Exact(dataset.left_unit.rig)
                                                : LoadCalibratedModel(o->left_model, o->model_kind);
    const AnyModel right = o->right_model.empty() ? AnyModel::Exact(dataset.right_unit.rig)
                                                  : LoadCalibratedModel(o->right_model, o->model_kind);
    depth::StereoDetectOptions detect;
    detect.markers.corner_refinement = o->corner_refinement;
    detect.marker_check_px = o->marker_check_px;
    std::vector<depth::PairDetection> detections;
    auto pairs =
        depth::DetectStereoPairs(dataset, left, right, detect, &detections, [&](const depth::PairDetection& d) {
          if (!global->quiet)
            std::fprintf(stderr, "  %s: %d corners left, %d right\n", d.pair.c_str(), d.left_corners, d.right_corners);
        });
    depth::StereoCalibrationOptions so;
    so.huber_px = o->huber;
    const depth::StereoRun run = OnInput(o->dataset, [&] {
      return depth::RunStereoCalibration(dataset, left, right, std::move(pairs), std::move(detections), so,
                                         o->corner_refinement);
    });
    nlohmann::json j = depth::StereoRunJson(run);
    j["tool"] = "hovs stereo-calibrate", j["versions"] = Versions(), j["dataset"] = o->dataset;
    StagedDirectory staged(o->out, "stereo-calibrate");
    depth::WriteStereoReport(staged.staging(), run, j);
    staged.Commit();
    if (!global->quiet) std::printf("%s", depth::StereoRunSummary(run).c_str());
    return 0;
  };
}

}  // namespace hovs::apps
