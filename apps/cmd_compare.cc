// hovs compare: the difference between two models of one camera as a map over the image (calib/model_diff.h):
// any pair of a scene's exact rig, OCamCalib's calib_results.txt, an OpenCV omnidir YAML and the models of a hovs
// calibration.json (--kind-a / --kind-b pick one of its models).
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "calib/model_diff.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "results/html.h"

namespace hovs::apps {
namespace {

AnyModel LoadCompared(const std::string& spec, const std::string& kind, const std::string& unit,
                      const std::string& option) {
  HOVS_REQUIRE(kind == "auto" || kind == "physical" || kind == "polynomial" || kind == "unified", option,
               "expected auto, physical, polynomial or unified (got '", kind, "')");
  if (kind == "auto") return LoadModelSpec(spec, unit, 10.0);
  RequireFile(spec, "model file");
  return LoadCalibratedModel(spec, kind);
}

}  // namespace

Runner SetupCompare(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string a, b, kind_a = "auto", kind_b = "auto", unit, out = "results/compare";
    calib::ModelDiffOptions diff;
    bool no_rotation = false;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("A", o->a, "model A: scene YAML, dataset.json, calib_results.txt, omnidir YAML or calibration.json")
      ->required();
  sub->add_option("B", o->b, "model B (same kinds; the same image size)")->required();
  sub->add_option("--kind-a", o->kind_a, "auto | physical | polynomial | unified: which model of a calibration.json")
      ->capture_default_str();
  sub->add_option("--kind-b", o->kind_b, "the same for B")->capture_default_str();
  sub->add_option("--unit", o->unit, "unit of a scene or manifest (default: the first)");
  AddBounded(sub, "--grid-step", &o->diff.grid_step_px, "grid step, px (0: about 120 columns)", 0, 10000);
  sub->add_flag("--no-rotation", o->no_rotation,
                "compare in the two models' own frames (default: after the rotation that best maps A onto B)");
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    o->diff.fit_rotation = !o->no_rotation;
    const AnyModel a = LoadCompared(o->a, o->kind_a, o->unit, "--kind-a");
    const AnyModel b = LoadCompared(o->b, o->kind_b, o->unit, "--kind-b");
    HOVS_REQUIRE(a.width() == b.width() && a.height() == b.height(), o->b, "is a model of ", b.width(), "x", b.height(),
                 " images but A (", o->a, ") of ", a.width(), "x", a.height(), ": not one camera");
    CheckOutputFolder(o->out, "compare", {o->a, o->b});
    const calib::ModelDiff d = calib::DiffModels(a, b, o->diff);
    nlohmann::json j = {{"tool", "hovs compare"},
                        {"versions", Versions()},
                        {"a", {{"file", o->a}, {"kind", a.KindName()}}},
                        {"b", {{"file", o->b}, {"kind", b.KindName()}}},
                        {"diff", calib::ModelDiffJson(d)},
                        {"note",
                         "per grid pixel: unprojected by A, turned by the best rotation onto B's frame, projected by "
                         "B; px = distance to the pixel, deg = angle to B's bearing of the pixel"}};
    const std::string summary =
        "hovs compare: " + std::string(a.KindName()) + " " + o->a + " vs " + b.KindName() + " " + o->b + "\n" + "  " +
        std::to_string(d.common_pixels) + " grid pixels in both domains (step " + std::to_string(d.step_px) +
        " px), frames " + FormatNumber("%.4f", d.rotation_deg) + " deg apart\n" + "  difference: median " +
        FormatNumber("%.4f", d.px_stats.median) + " px, 95 % " + FormatNumber("%.4f", d.px_stats.p95) + " px, max " +
        FormatNumber("%.4f", d.px_stats.max) + " px; median " + FormatNumber("%.5f", d.deg_stats.median) +
        " deg, 95 % " + FormatNumber("%.5f", d.deg_stats.p95) + " deg\n";
    StagedDirectory stage(o->out, "compare", {o->a, o->b});
    std::filesystem::create_directories(stage.staging() / "figures");
    calib::WriteModelDiffFigures(d, "A vs B", stage.staging() / "figures/diff_px.png",
                                 stage.staging() / "figures/diff_deg.png");
    WriteFileAtomic(stage.staging() / "compare.json", j.dump(2) + "\n");
    WriteFileAtomic(stage.staging() / "summary.txt", summary);
    results::HtmlPage page("hovs compare");
    page.Paragraph("A: " + o->a + " (" + a.KindName() + "); B: " + o->b + " (" + b.KindName() + ").");
    page.Paragraph(summary);
    page.Figure("figures/diff_px.png", "difference, pixels", 800);
    page.Figure("figures/diff_deg.png", "difference, degrees", 800);
    page.Link("The figures: ", "compare.json", "compare.json", ".");
    WriteFileAtomic(stage.staging() / "index.html", page.Render());
    stage.Commit();
    if (global->json)
      std::cout << j.dump(2) << "\n";
    else if (!global->quiet)
      std::cout << summary;
    return 0;
  };
}

}  // namespace hovs::apps
