// hovs convert: a camera model into the files other tools read (calib/camera_formats.h): Kalibr's camchain, the
// MEI YAML of CamOdoCal and VINS-Fusion, and refits to double sphere, extended unified and Kannala-Brandt
// (calib/model_refit.h) with the refit's error over the source's calibrated field.
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "calib/camera_formats.h"
#include "calib/model_refit.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"

namespace hovs::apps {

Runner SetupConvert(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string model, kind = "auto", unit, to, name = "camera", out = "results/convert";
    int grid_step = 0;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("MODEL", o->model,
                  "scene YAML, dataset.json, calib_results.txt, omnidir or MEI YAML, Kalibr camchain or "
                  "calibration.json")
      ->required();
  sub->add_option("--to", o->to,
                  "kalibr (camchain, omni + radtan) | mei (CamOdoCal / VINS-Fusion) | ds | eucm | kb (refits, "
                  "written as a Kalibr camchain)")
      ->required();
  sub->add_option("--kind", o->kind, "auto | physical | polynomial | unified: which model of a calibration.json")
      ->capture_default_str();
  sub->add_option("--unit", o->unit, "unit of a scene or manifest, camN of a camchain (default: the first)");
  sub->add_option("--camera-name", o->name, "camera_name of a MEI file")->capture_default_str();
  AddBounded(sub, "--grid-step", &o->grid_step, "refit grid step, px (0: about 60 columns)", 0, 10000);
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    HOVS_REQUIRE(o->to == "kalibr" || o->to == "mei" || o->to == "ds" || o->to == "eucm" || o->to == "kb", "--to",
                 "expected kalibr, mei, ds, eucm or kb (got '", o->to, "')");
    HOVS_REQUIRE(o->kind == "auto" || o->kind == "physical" || o->kind == "polynomial" || o->kind == "unified",
                 "--kind", "expected auto, physical, polynomial or unified (got '", o->kind, "')");
    HOVS_REQUIRE(std::filesystem::exists(o->model), o->model, "file not found");
    const AnyModel source =
        o->kind == "auto" ? LoadModelSpec(o->model, o->unit, 10.0) : LoadCalibratedModel(o->model, o->kind, 10.0);
    CheckOutputFolder(o->out, "convert", {o->model});
    // The unified model itself when the source is one (exact); otherwise a refit.
    const bool exact = (o->to == "kalibr" || o->to == "mei") && source.kind() == AnyModel::Kind::kUnified;
    std::optional<calib::Refit> refit;
    if (!exact) {
      calib::RefitOptions ro;
      ro.kind = o->to == "kalibr" || o->to == "mei" ? "omni" : o->to;
      ro.grid_step_px = o->grid_step;
      refit = calib::RefitModel(source, ro);
    }
    std::string file, text;
    if (o->to == "mei") {
      file = "mei.yaml";
      text = calib::FormatMeiYaml(exact ? source.unified() : *refit->unified, o->name);
    } else {
      file = "camchain.yaml";
      text = calib::FormatKalibrCamchain({exact ? calib::KalibrFromUnified(source.unified())
                                                : calib::KalibrFromRefit(*refit, source.width(), source.height())});
    }
    nlohmann::json j = {{"tool", "hovs convert"},
                        {"versions", Versions()},
                        {"source", {{"file", o->model}, {"kind", source.KindName()}}},
                        {"to", o->to},
                        {"file", file},
                        {"exact", exact}};
    std::string summary = "hovs convert: " + std::string(source.KindName()) + " " + o->model + " -> " + file;
    if (refit) {
      j["refit"] = calib::RefitJson(*refit);
      summary += " (" + refit->kind + " refit over " + std::to_string(refit->pixels) + " grid pixels of the source's " +
                 FormatNumber("%.1f", refit->field_deg) + " deg field: median " +
                 FormatNumber("%.4f", refit->px.median) + " px, 95 % " + FormatNumber("%.4f", refit->px.p95) +
                 " px, max " + FormatNumber("%.4f", refit->px.max) + " px" +
                 (refit->outside ? ", " + std::to_string(refit->outside) + " outside its domain" : "") + ")";
    } else {
      summary += " (the unified model as it is)";
    }
    summary += "\n";
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
