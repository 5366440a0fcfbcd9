#include "apps/validation.h"

#include <cmath>
#include <cstdio>

#include "apps/commands.h"
#include "core/error.h"
#include "core/io.h"
#include "results/html.h"

namespace hovs::apps {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

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
    const auto pct = [](double v) { return std::isfinite(v) ? Fmt("%.3f %%", 100 * v) : std::string("n/a"); };
    for (const auto& [label, key] :
         {std::pair<std::string, std::string>{"exact models (the calibration alone)", "stereo_exact_models"},
          {"calibrated physical models (the whole chain)", "stereo"}}) {
      if (!f.contains(key)) continue;
      const json& s = f[key];
      rows.push_back({label, Fmt("%.5f", Num(s, {"baseline_m"})), Fmt("%.4f", 1e3 * Num(s, {"sigma_baseline_m"})),
                      Fmt("%.3f", Num(s, {"ground_truth", "baseline_error_mm"})),
                      Fmt("%.4f", Num(s, {"ground_truth", "rotation_error_deg"})), Fmt("%.3f", Num(s, {"rms_px"})),
                      Fmt("%.0f", Num(s, {"sparse_depth", "points"})),
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
    for (const auto& [view, v] : f["views"]["psnr_db"].items()) rows.push_back({view, Fmt("%.2f", v.get<double>())});
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
      rows.push_back({Fmt("%.0f", b["band_m"][0].get<double>()) + "-" + Fmt("%.0f", b["band_m"][1].get<double>()),
                      std::to_string(b["pixels"].get<int>()), Fmt("%.1f %%", 100 * b["valid_fraction"].get<double>()),
                      b["median_relative_error"].is_null()
                          ? "n/a"
                          : Fmt("%.2f %%", 100 * b["median_relative_error"].get<double>()),
                      Fmt("%.1f %%", 100 * b["within_5_percent_fraction"].get<double>())});
    page.Table({"band (m)", "pixels", "valid", "median rel. error", "within 5 % (of all)"}, rows);
    page.Paragraph("Dense matching time: " + Fmt("%.0f ms", f["depth"]["dense_ms"].get<double>()));
    fig("depth/rectified_left.png", "left unit rectified around the baseline", 900);
    fig("depth/error_map.png", "relative error, 0 (blue) to 5 % or more (red); black: masked", 900);
  }
  if (f.contains("real")) {
    page.Heading("Real images (../shared/data/vmr): no ground truth");
    page.Paragraph(
        "Checked: detection on every image, calibration residuals, the same corners through OpenCV's "
        "omnidir. Not checkable without ground truth: ray accuracy, the detector's absolute error.");
    const json& r = f["real"];
    page.Table({"images", "boards found", "corners from the board's edges", "polynomial RMS (px)", "unified RMS (px)",
                "OpenCV omnidir RMS, same corners (px)", "target (px)"},
               {{Fmt("%.0f", Num(r, {"images"})), Fmt("%.0f", Num(r, {"boards_found"})),
                 Fmt("%.0f", Num(r, {"corners_from_edges"})), Fmt("%.4f", Num(r, {"polynomial_rms_px"})),
                 Fmt("%.4f", Num(r, {"unified_rms_px"})), Fmt("%.4f", Num(r, {"opencv_omnidir_rms_px"})),
                 Fmt("%.2f", Num(r, {"target_rms_px"}))}});
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

Preset MakePreset(const std::string& name) {
  Preset p;
  p.name = name;
  if (name == "full") return p;
  HOVS_REQUIRE(name == "reduced", "--preset", "unknown preset '", name, "' (full | reduced)");
  // Half resolution (the same optics, 5.5 Mpx -> 1.4 Mpx), fewer frames and samples: about a minute and a half.
  p.downscale = 2;
  p.mono_count = 6, p.mono_samples = 2;
  p.stereo_count = 6, p.stereo_samples = 1;
  p.street_samples = 2, p.truth_samples = 1;
  p.depth_width = 1024, p.depth_height = 256, p.disparities = 160;
  p.design = false;
  // Pixel figures double at half resolution; angles and ranges get the same relative slack.
  p.detection_rms_px = 0.3, p.calibration_rms_px = 0.3;
  p.baseline_mm = 1.0, p.rotation_deg = 0.04, p.sparse_rel = 0.01;
  // The left unit's physical model at half resolution is off by about 0.25 deg (see the ray-angle targets): its
  // views reach 25 dB against the truth renders; the guard only catches gross breakage there.
  p.min_psnr_db = 23, p.dense_median_rel = 0.03;
  return p;
}

double Num(const json& j, const std::vector<std::string>& path) {
  const json* x = &j;
  for (const auto& k : path) {
    if (!x->is_object() || !x->contains(k)) return NAN;
    x = &(*x)[k];
  }
  return x->is_number() ? x->get<double>() : NAN;
}

Validation::Validation(Preset p, fs::path out, fs::path target, uint64_t seed, std::string source_dir, bool quiet)
    : p_(std::move(p)),
      out_(std::move(out)),
      target_(std::move(target)),
      seed_(seed),
      src_(std::move(source_dir)),
      quiet_(quiet) {
  metrics_ = {{"tool", "hovs validate"},
              {"versions", Versions()},
              {"status", "running"},
              {"config",
               {{"preset", p_.name},
                {"seed", seed_},
                {"downscale", p_.downscale},
                {"mono_frames", p_.mono_count},
                {"mono_samples", p_.mono_samples},
                {"stereo_pairs", p_.stereo_count},
                {"stereo_samples", p_.stereo_samples},
                {"street_samples", p_.street_samples},
                {"truth_samples", p_.truth_samples},
                {"depth", {p_.depth_width, p_.depth_height, p_.disparities}},
                {"thresholds",
                 {{"detection_rms_px", p_.detection_rms_px},
                  {"calibration_rms_px", p_.calibration_rms_px},
                  {"baseline_error_mm", p_.baseline_mm},
                  {"rotation_error_deg", p_.rotation_deg},
                  {"sparse_depth_max_rel", p_.sparse_rel},
                  {"min_view_psnr_db", p_.min_psnr_db},
                  {"dense_median_rel_1_8m", p_.dense_median_rel}}}}},
              {"stages", json::array()},
              {"checks", json::array()},
              {"figures", json::object()}};
}

void Validation::Stage(const std::string& name, const std::vector<std::vector<std::string>>& commands,
                       const std::function<void()>& collect) {
  const int index = static_cast<int>(metrics_["stages"].size()) + 1;
  if (!quiet_) std::fprintf(stderr, "[validate %d] %s\n", index, name.c_str());
  const auto t0 = std::chrono::steady_clock::now();
  json stage = {{"name", name}, {"commands", json::array()}};
  try {
    for (auto args : commands) {
      // The command as it reads in the finished report: paths in the target folder, not in the staging one.
      std::string line = "hovs";
      for (const auto& a : args) line += " " + Displayed(a);
      stage["commands"].push_back(line);
      if (quiet_) args.insert(args.begin(), "--quiet");
      const int rc = RunCommandLine(args, true);
      HOVS_REQUIRE(rc == 0, name, "`", line, "` exited with ", rc);
    }
    if (collect) collect();
  } catch (const Error& e) {
    stage["seconds"] = Seconds(t0);
    stage["status"] = "failed";
    stage["error"] = e.what();
    metrics_["stages"].push_back(stage);
    metrics_["status"] = "partial: stage '" + name + "' failed";
    Write();
    throw Error("validate stage '" + name + "'", e.what());
  }
  stage["seconds"] = Seconds(t0);
  stage["status"] = "done";
  metrics_["stages"].push_back(stage);
  Write();
}

void Validation::Skip(const std::string& name, const std::string& why) {
  metrics_["stages"].push_back({{"name", name}, {"status", "not run"}, {"reason", why}, {"seconds", 0}});
  if (!quiet_) std::fprintf(stderr, "[validate] %s: not run (%s)\n", name.c_str(), why.c_str());
}

void Validation::Check(const std::string& name, double value, const std::string& kind, double limit,
                       const std::string& unit, const std::string& source, bool gate) {
  const bool pass = std::isfinite(value) && (kind == "max" ? value <= limit : value >= limit);
  metrics_["checks"].push_back({{"name", name},
                                {"value", std::isfinite(value) ? json(value) : json()},
                                {"limit", limit},
                                {"kind", kind},
                                {"unit", unit},
                                {"pass", pass},
                                {"gate", gate},
                                {"source", source}});
}

int Validation::Failed() const {
  int n = 0;
  for (const auto& c : metrics_["checks"]) n += c["gate"].get<bool>() && !c["pass"].get<bool>();
  return n;
}

void Validation::Finish(double seconds) {
  int missed = 0;
  for (const auto& c : metrics_["checks"]) missed += !c["gate"].get<bool>() && !c["pass"].get<bool>();
  metrics_["status"] =
      (Failed() ? "complete, " + std::to_string(Failed()) + " gates FAILED" : "complete, all gates pass") +
      (missed ? ", " + std::to_string(missed) + " targets not met yet" : std::string());
  metrics_["seconds"] = seconds;
  Write();
  WriteFileAtomic(out_ / "summary.txt", Summary());
}

std::string Validation::Displayed(std::string text) const {
  const std::string staging = out_.string(), target = target_.string();
  for (size_t at = text.find(staging); at != std::string::npos; at = text.find(staging, at + target.size()))
    text.replace(at, staging.size(), target);
  return text;
}

std::string Validation::Summary() const {
  std::string s = "hovs validate (" + p_.name + "): " + metrics_["status"].get<std::string>() + " -> " +
                  (target_ / "report.html").string() + "\n";
  for (const auto& c : metrics_["checks"]) {
    const std::string v = c["value"].is_null() ? "n/a" : Fmt("%.4g", c["value"].get<double>());
    const bool gate = c["gate"].get<bool>(), pass = c["pass"].get<bool>();
    s += std::string(gate ? (pass ? "  ok       " : "  FAIL     ") : (pass ? "  met      " : "  not met  ")) +
         c["name"].get<std::string>() + (gate ? "" : " [target]") + ": " + v + " " + c["unit"].get<std::string>() +
         " (" + (c["kind"] == "max" ? "<= " : ">= ") + Fmt("%.4g", c["limit"].get<double>()) + ")\n";
  }
  for (const auto& st : metrics_["stages"])
    s += "  stage " + st["name"].get<std::string>() + ": " + st["status"].get<std::string>() + ", " +
         Fmt("%.1f s", st["seconds"].get<double>()) + "\n";
  return s;
}

void Validation::Write() const {
  WriteFileAtomic(out_ / "metrics.json", metrics_.dump(1) + "\n");
  WriteFileAtomic(out_ / "report.html", Report());
}

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
    rows.push_back({c["name"], c["value"].is_null() ? "n/a" : Fmt("%.4g", c["value"].get<double>()),
                    std::string(c["kind"] == "max" ? "<= " : ">= ") + Fmt("%.4g", c["limit"].get<double>()), c["unit"],
                    c["gate"].get<bool>() ? "gate" : "target",
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
    rows.push_back({st["name"], st["status"], Fmt("%.1f", st["seconds"].get<double>()),
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
  if (f.contains("calibration")) {
    page.Heading("Detection and monocular calibration (both units)");
    rows.clear();
    for (const auto& [unit, c] : f["calibration"].items())
      rows.push_back(
          {unit, std::to_string(c["boards_found"].get<int>()) + " / " + std::to_string(c["images"].get<int>()),
           Fmt("%.4f", c["detection_rms_px"].get<double>()), Fmt("%.4f", c["rms_px"].get<double>()),
           Fmt("%.5f", c["mean_ray_angle_deg"].get<double>()), Fmt("%.5f", c["max_ray_angle_deg"].get<double>()),
           Fmt("%.5f", c["mean_ray_angle_aligned_deg"].get<double>()),
           Fmt("%.4f", c["frame_rotation_deg"].get<double>()), Fmt("%.4f", c["physical_rms_px"].get<double>()),
           Fmt("%.5f", c["physical_mean_ray_angle_deg"].get<double>()),
           Fmt("%.4f", c["physical_tilt_error_deg"].get<double>()),
           Fmt("%.3f", c["physical_centre_error_mm"].get<double>())});
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
