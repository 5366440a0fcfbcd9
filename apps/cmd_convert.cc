// hovs convert: a camera model into the files other tools read (calib/camera_formats.h): Kalibr's camchain, the
// MEI YAML of CamOdoCal and VINS-Fusion, and refits to double sphere, extended unified and Kannala-Brandt
// (calib/model_refit.h) with the refit's error over the source's calibrated field.
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "calib/camera_formats.h"
#include "calib/omnidir_io.h"
#include "calib/model_refit.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "core/json.h"
#include "scenes/ground_truth.h"

namespace hovs::apps {

Runner SetupConvert(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string model, kind = "auto", unit, to, name = "camera", out = "results/convert", right, stereo, size;
    int grid_step = 0;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("MODEL", o->model,
                  "scene YAML, dataset.json, calib_results.txt, omnidir or MEI YAML, Kalibr camchain or "
                  "calibration.json")
      ->required();
  sub->add_option("--to", o->to,
                  "kalibr (camchain, omni + radtan) | mei (CamOdoCal / VINS-Fusion) | omnidir (OpenCV omnidir YAML) | "
                  "ds | eucm | kb (refits, written as a Kalibr camchain) | basalt (double-sphere refit, Basalt's JSON)")
      ->required();
  sub->add_option("--image-size", o->size,
                  "WxH: the image size of a model file that has none (OpenCV's omni_calibration sample output)");
  sub->add_option("--kind", o->kind, "auto | physical | polynomial | unified: which model of a calibration.json")
      ->capture_default_str();
  sub->add_option("--unit", o->unit, "unit of a scene or manifest, camN of a camchain (default: the first)");
  sub->add_option("--right", o->right, "the right unit's model (same kinds): a two-camera camchain with --stereo");
  sub->add_option("--stereo", o->stereo, "hovs stereo-calibrate's stereo.json: cam1's T_cn_cnm1");
  sub->add_option("--camera-name", o->name, "camera_name of a MEI file")->capture_default_str();
  AddBounded(sub, "--grid-step", &o->grid_step, "refit grid step, px (0: about 60 columns)", 0, 10000);
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    const bool unified_file = o->to == "kalibr" || o->to == "mei" || o->to == "omnidir";
    HOVS_REQUIRE(unified_file || o->to == "ds" || o->to == "eucm" || o->to == "kb" || o->to == "basalt", "--to",
                 "expected kalibr, mei, omnidir, ds, eucm, kb or basalt (got '", o->to, "')");
    if (o->to == "mei") calib::CheckMeiCameraName(o->name, "--camera-name");
    ImageSize size;
    if (!o->size.empty()) ParseImageSize(o->size, "--image-size", &size.width, &size.height);
    HOVS_REQUIRE(o->kind == "auto" || o->kind == "physical" || o->kind == "polynomial" || o->kind == "unified",
                 "--kind", "expected auto, physical, polynomial or unified (got '", o->kind, "')");
    RequireFile(o->model, "model file");
    const AnyModel source = o->kind == "auto" ? LoadModelSpec(o->model, o->unit, 10.0, size)
                                              : LoadCalibratedModel(o->model, o->kind, 10.0, size);
    CheckOutputFolder(o->out, "convert", {o->model});
    HOVS_REQUIRE(o->right.empty() == o->stereo.empty(), o->right.empty() ? "--stereo" : "--right",
                 "a two-camera camchain needs both --right and --stereo");
    HOVS_REQUIRE(o->right.empty() || (o->to != "mei" && o->to != "omnidir"), "--right",
                 "a MEI or omnidir file holds one camera; use --to kalibr");
    std::vector<AnyModel> sources = {source};
    Rigid3d right_from_left;
    if (!o->right.empty()) {
      sources.push_back(o->kind == "auto" ? LoadModelSpec(o->right, o->unit, 10.0)
                                          : LoadCalibratedModel(o->right, o->kind, 10.0));
      const auto sj = ReadJsonFile(o->stereo);
      HOVS_REQUIRE(sj.is_object() && sj.contains("right_from_left"), o->stereo,
                   "not a hovs stereo-calibrate result (no right_from_left)");
      right_from_left = scenes::PoseFromJson(sj["right_from_left"], o->stereo + " (right_from_left)");
    }
    nlohmann::json j = {{"tool", "hovs convert"}, {"versions", Versions()}, {"to", o->to}};
    std::string summary;
    std::vector<calib::KalibrCamera> cams;
    std::vector<double> gamma;
    std::optional<UnifiedModel<double>> mei;
    for (size_t k = 0; k < sources.size(); ++k) {
      const AnyModel& src = sources[k];
      const std::string file = k == 0 ? o->model : o->right;
      // The unified model itself when the source is one (exact); otherwise a refit.
      const bool exact = unified_file && src.kind() == AnyModel::Kind::kUnified;
      nlohmann::json cj = {{"file", file}, {"kind", src.KindName()}, {"exact", exact}};
      summary += "hovs convert: " + std::string(src.KindName()) + " " + file;
      if (exact) {
        cams.push_back(calib::KalibrFromUnified(src.unified()));
        mei = src.unified();
        gamma.push_back(0);
        summary += " (the unified model as it is)\n";
      } else {
        calib::RefitOptions ro;
        ro.kind = unified_file ? "omni" : o->to == "basalt" ? "ds" : o->to;
        ro.grid_step_px = o->grid_step;
        const calib::Refit refit = calib::RefitModel(src, ro);
        cams.push_back(calib::KalibrFromRefit(refit, src.width(), src.height()));
        if (refit.unified) mei = *refit.unified;
        gamma.push_back(refit.axis_rotation_deg * M_PI / 180);
        cj["refit"] = calib::RefitJson(refit);
        summary += " (" + refit.kind + " refit over " + std::to_string(refit.pixels) + " grid pixels of its " +
                   FormatNumber("%.1f", refit.field_deg) + " deg field: median " +
                   FormatNumber("%.4f", refit.px.median) + " px, 95 % " + FormatNumber("%.4f", refit.px.p95) +
                   " px, max " + FormatNumber("%.4f", refit.px.max) + " px" +
                   (refit.outside ? ", " + std::to_string(refit.outside) + " outside its domain" : "") +
                   "; its frame turned " + FormatNumber("%.4f", refit.axis_rotation_deg) + " deg about the axis)\n";
      }
      j["cameras"].push_back(cj);
    }
    if (cams.size() == 2) cams[1].T_cn_cnm1 = calib::ToolsFromMirrorPose(right_from_left, gamma[0], gamma[1]);
    const std::string file = o->to == "mei"       ? "mei.yaml"
                             : o->to == "omnidir" ? "unified.yaml"
                             : o->to == "basalt"  ? "basalt_calib.json"
                                                  : "camchain.yaml";
    calib::OmnidirFile omnidir;
    if (mei) omnidir.model = *mei;
    const std::string text = o->to == "mei"       ? calib::FormatMeiYaml(*mei, o->name)
                             : o->to == "omnidir" ? calib::FormatOmnidirYaml(omnidir)
                             : o->to == "basalt"  ? calib::FormatBasaltCalibration(cams)
                                                  : calib::FormatKalibrCamchain(cams);
    j["file"] = file;
    summary += "  -> " + file + "\n";
    StagedDirectory stage(o->out, "convert", {o->model});
    WriteFileAtomic(stage.staging() / file, text);
    WriteFileAtomic(stage.staging() / "convert.json", j.dump(2) + "\n");
    WriteFileAtomic(stage.staging() / "summary.txt", summary);
    stage.Commit();
    if (!global->quiet) std::cout << summary;
    return 0;
  };
}

}  // namespace hovs::apps
