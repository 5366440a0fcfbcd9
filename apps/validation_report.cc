// The page of hovs validate (report.html): checks, stages, and per stage its figures as tables and plots, from
// the run's metrics; every figure's JSON is behind the link to metrics.json.
#include "apps/validation.h"

#include <cmath>
#include <cstdio>

#include "apps/commands.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "results/html.h"

namespace hovs::apps {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// The report's later sections (stereo, views, dense depth, real images, configuration), from the figures.
void LaterSections(results::HtmlPage& page, const json& m, const fs::path& out) {
  const auto& f = m["figures"];
  std::vector<std::vector<std::string>> rows;
  auto fig = [&](const std::string& rel, const std::string& caption, int width) {
    if (fs::exists(out / rel)) page.Figure(rel, caption, width);
  };
  if (f.contains("stereo")) {
    page.Heading("Stereo calibration and sparse depth");
    rows.clear();
    const auto pct = [](double v) { return std::isfinite(v) ? FormatNumber("%.3f %%", 100 * v) : std::string("n/a"); };
    for (const auto& [label, key] :
         {std::pair<std::string, std::string>{"exact models (the calibration alone)", "stereo_exact_models"},
          {"calibrated physical models (the whole chain)", "stereo"}}) {
      if (!f.contains(key)) continue;
      const json& s = f[key];
      rows.push_back({label, FormatNumber("%.5f", Num(s, {"baseline_m"})),
                      FormatNumber("%.4f", 1e3 * Num(s, {"sigma_baseline_m"})),
                      FormatNumber("%.3f", Num(s, {"ground_truth", "baseline_error_mm"})),
                      FormatNumber("%.4f", Num(s, {"ground_truth", "rotation_error_deg"})),
                      FormatNumber("%.3f", Num(s, {"rms_px"})),
                      FormatNumber("%.0f", Num(s, {"sparse_depth", "points"})),
                      pct(Num(s, {"sparse_depth", "median_rel_error"})), pct(Num(s, {"sparse_depth", "p95_rel_error"})),
                      pct(Num(s, {"sparse_depth", "max_rel_error"})),
                      pct(Num(s, {"sparse_depth", "conditioned", "max_rel_error"}))});
    }
    page.Table(
        {"models", "baseline (m)", "sigma (mm)", "baseline error (mm)", "rotation error (deg)", "reprojection RMS (px)",
         "sparse points", "median |rel. error|", "95th percentile", "worst", "worst, >= 15 deg from the baseline"},
        rows);
    page.Paragraph(
        "Sparse depth: every ArUco corner seen by both units, triangulated with the calibrated pose and "
        "models, against its true range. The worst points lie near the baseline direction, where a pixel "
        "of disparity is a large part of the range (the plots below, calibrated models).");
    fig("stereo/figures/depth_error_vs_range.png", "|relative depth error| against range (calibrated models)", 640);
    fig("stereo/figures/depth_error_vs_angle.png", "|relative depth error| against the angle to the baseline", 640);
    fig("stereo/figures/frame0_left.png", "reprojection, frame 0, left unit (residuals x20)", 420);
    page.Link("Per-pair errors, the worst points and every corner: ", "stereo/index.html", "stereo/index.html",
              " (calibrated models), stereo-exact/index.html (exact models), and their stereo.json.");
  }
  if (f.contains("views")) {
    page.Heading("Six-view expansion (calibrated left model) beside pinhole truth renders");
    rows.clear();
    for (const auto& [view, v] : f["views"]["psnr_db"].items())
      rows.push_back({view, FormatNumber("%.2f", v.get<double>())});
    page.Table({"view", "PSNR against the truth render (dB)"}, rows);
    for (const auto& [view, v] : f["views"]["files"].items()) {
      fig("views/" + v[0].get<std::string>(), view + ": unwrapped", 360);
      fig("views/" + v[1].get<std::string>(), view + ": pinhole truth", 360);
    }
    fig("panorama/" + f["views"].value("panorama", std::string("none")), "cylindrical panorama (calibrated model)",
        900);
  }
  if (f.contains("depth")) {
    page.Heading("Dense depth (calibrated models and pose) against the range channel");
    rows.clear();
    for (const auto& b : f["depth"]["bands"])
      rows.push_back({FormatNumber("%.0f", b["band_m"][0].get<double>()) + "-" +
                          FormatNumber("%.0f", b["band_m"][1].get<double>()),
                      std::to_string(b["pixels"].get<int>()),
                      FormatNumber("%.1f %%", 100 * b["valid_fraction"].get<double>()),
                      b["median_relative_error"].is_null()
                          ? "n/a"
                          : FormatNumber("%.2f %%", 100 * b["median_relative_error"].get<double>()),
                      FormatNumber("%.1f %%", 100 * b["within_5_percent_fraction"].get<double>())});
    page.Table({"band (m)", "pixels", "valid", "median rel. error", "within 5 % (of all)"}, rows);
    page.Paragraph("Dense matching time: " + FormatNumber("%.0f ms", f["depth"]["dense_ms"].get<double>()));
    fig("depth/rectified_left.png", "left unit rectified around the baseline", 900);
    fig("depth/error_map.png", "relative error, 0 (blue) to 5 % or more (red); black: masked", 900);
  }
  if (f.contains("real")) {
    page.Heading("Real images (../shared/data/vmr): no ground truth");
    page.Paragraph(
        "Checked: detection on every image, calibration residuals, the same corners through OpenCV's "
        "omnidir. Not checkable without ground truth: ray accuracy, the detector's absolute error.");
    const json& r = f["real"];
    page.Table(
        {"images", "boards found", "corners from the board's edges", "polynomial RMS (px)", "unified RMS (px)",
         "OpenCV omnidir RMS, same corners (px)", "target (px)"},
        {{FormatNumber("%.0f", Num(r, {"images"})), FormatNumber("%.0f", Num(r, {"boards_found"})),
          FormatNumber("%.0f", Num(r, {"corners_from_edges"})), FormatNumber("%.4f", Num(r, {"polynomial_rms_px"})),
          FormatNumber("%.4f", Num(r, {"unified_rms_px"})), FormatNumber("%.4f", Num(r, {"opencv_omnidir_rms_px"})),
          FormatNumber("%.2f", Num(r, {"target_rms_px"}))}});
    page.Link("The calibration's report: ", "real/calib/index.html", "real/calib/index.html", ".");
    fig("real/calib/figures/VMRImage0.png", "VMRImage0: detected corners and reprojection (residuals x20)", 420);
    fig("real/panorama/VMRImage0/panorama.png", "panorama of VMRImage0 with the calibrated model", 900);
  }
  page.Heading("Configuration and versions");
  rows.clear();
  for (const auto& [key, value] : m["config"].items()) {
    if (!value.is_object()) {
      rows.push_back({key, value.dump()});
      continue;
    }
    for (const auto& [sub, v] : value.items()) rows.push_back({key + "." + sub, v.dump()});
  }
  page.Table({"setting", "value"}, rows);
  rows.clear();
  for (const auto& [name, version] : m["versions"].items())
    rows.push_back({name, version.is_string() ? version.get<std::string>() : version.dump()});
  page.Table({"library", "version"}, rows);
  page.Link("Every figure of this page: ", "metrics.json", "metrics.json", ".");
}

}  // namespace

std::string Validation::Report() const {
  const json& m = metrics_;
  results::HtmlPage page("hovs validate: " + p_.name);
  page.Paragraph("Status: " + m["status"].get<std::string>() +
                 ". Every figure below is measured against the "
                 "renderer's ground truth (synthetic stages) or reported as is (real images). Command and versions at "
                 "the end; metrics.json holds every figure.");
  page.Heading("Checks");
  std::vector<std::vector<std::string>> rows;
  for (const auto& c : m["checks"])
    rows.push_back({c["name"], c["value"].is_null() ? "n/a" : FormatNumber("%.4g", c["value"].get<double>()),
                    std::string(c["kind"] == "max" ? "<= " : ">= ") + FormatNumber("%.4g", c["limit"].get<double>()),
                    c["unit"], c["gate"].get<bool>() ? "gate" : "target",
                    c["gate"].get<bool>() ? (c["pass"].get<bool>() ? "pass" : "FAIL")
                                          : (c["pass"].get<bool>() ? "met" : "not met yet"),
                    c["source"]});
  page.Table({"check", "value", "threshold", "unit", "kind", "result", "from"}, rows);
  page.Paragraph(
      "Gates must pass (hovs validate exits 1 otherwise; CI runs the reduced preset). Targets are goals "
      "of the issues that hovs does not reach yet; they are measured on every run so the gap stays visible.");
  page.Heading("Stages and timing");
  rows.clear();
  for (const auto& st : m["stages"])
    rows.push_back({st["name"], st["status"], FormatNumber("%.1f", st["seconds"].get<double>()),
                    st.contains("error")    ? st["error"].get<std::string>()
                    : st.contains("reason") ? st["reason"].get<std::string>()
                                            : ""});
  page.Table({"stage", "status", "seconds", "note"}, rows);
  const auto& f = m["figures"];
  auto fig = [&](const std::string& rel, const std::string& caption, int width) {
    if (fs::exists(out_ / rel)) page.Figure(rel, caption, width);
  };
  if (f.contains("design")) {
    page.Heading("Design study");
    page.Preformatted(f["design"].get<std::string>());
    fig("design/figures/feasible_region.png", "feasible (a, b) region and the optima", 420);
    fig("design/figures/vertical_field.png", "vertical field of view over (a, b)", 420);
    page.Paragraph("Full design report: design/index.html");
  }
  if (f.contains("edge_check")) {
    page.Heading("Optics: rendered slanted edges against the predicted MTF50");
    page.Preformatted(f["edge_check"].get<std::string>());
  }
  if (f.contains("calibration")) {
    page.Heading("Detection and monocular calibration (both units)");
    rows.clear();
    for (const auto& [unit, c] : f["calibration"].items())
      rows.push_back(
          {unit, std::to_string(c["boards_found"].get<int>()) + " / " + std::to_string(c["images"].get<int>()),
           FormatNumber("%.4f", c["detection_rms_px"].get<double>()), FormatNumber("%.4f", c["rms_px"].get<double>()),
           FormatNumber("%.5f", c["mean_ray_angle_deg"].get<double>()),
           FormatNumber("%.5f", c["max_ray_angle_deg"].get<double>()),
           FormatNumber("%.5f", c["mean_ray_angle_aligned_deg"].get<double>()),
           FormatNumber("%.4f", c["frame_rotation_deg"].get<double>()),
           FormatNumber("%.4f", c["physical_rms_px"].get<double>()),
           FormatNumber("%.5f", c["physical_mean_ray_angle_deg"].get<double>()),
           FormatNumber("%.4f", c["physical_tilt_error_deg"].get<double>()),
           FormatNumber("%.3f", c["physical_centre_error_mm"].get<double>())});
    page.Table({"unit", "boards found", "detection RMS vs exact corners (px)", "polynomial RMS (px)",
                "polynomial: mean ray angle vs true rig (deg)", "max (deg)", "mean, frame rotation removed (deg)",
                "frame rotation (deg)", "physical RMS (px)", "physical: mean ray angle (deg)",
                "physical: tilt error (deg)", "physical: camera centre error (mm)"},
               rows);
    page.Paragraph(
        "The later stages use each unit's physical model (mirror at its design a, b; camera tilt and offset "
        "calibrated; camera intrinsics held at the camera's own calibration, here its design values).");
    fig("data/mono-left/thumbs/left_0000.png", "a rendered calibration image (left unit)", 360);
    fig("calib-left/figures/left_0000.png", "detection and reprojection, left unit (residuals x20)", 420);
    fig("calib-right/figures/right_0000.png", "detection and reprojection, right unit (residuals x20)", 420);
    fig("data/mono-right/thumbs/right_0000.png", "a rendered calibration image (right unit, misaligned)", 360);
  }
  LaterSections(page, m, out_);
  return page.Render();
}

}  // namespace hovs::apps
