// hovs validate: the whole chain on the reference design, every stage against ground truth, one report.
//
//   design study -> renders (a monocular calibration set per unit of the binocular rig, ArUco stereo pairs, the
//   street scene) -> checkerboard detection + monocular calibration of both units -> stereo calibration with the
//   calibrated models (+ sparse depth of the marker corners) -> six-view expansion and panorama of the street with
//   the calibrated model, against pinhole renders -> dense depth of the street with the calibrated models and pose,
//   against the range channel -> the real images of ../shared/data/vmr (detection, calibration beside OpenCV's
//   omnidir, a panorama; no ground truth there).
//
// Each stage runs the same code as its subcommand (in process, through the command table) and writes into
// <out>/<stage folder>; metrics.json and report.html are rewritten after every stage, so a run stopped by bad
// input leaves valid partial results that say they are partial and which stage failed. Checks compare figures
// with the thresholds of the issues (scaled for the reduced preset, which renders at half resolution).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "results/html.h"
#include "results/plot.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

struct Preset {
  std::string name;
  int downscale = 1;
  // Calibration sets at 16 samples per pixel (4 x 4 stratified), close to the noise-free render: at 4
  // the render's own sampling moves the corners by 0.05 px RMS and the polynomial model's rays by 0.018 deg.
  int mono_count = 9, mono_samples = 16;
  // Stereo pairs at 4 samples per pixel (a 2 x 2 stratified grid): at 2 (random jitter) the marker edges are
  // nearly binary and far corners are found to 0.3-0.5 px only (sparse depth worst 1.8 % vs 0.8 % at 4).
  int stereo_count = 12, stereo_samples = 4;
  int street_samples = 4, truth_samples = 4;
  int depth_width = 2048, depth_height = 512, disparities = 320;
  bool design = true, real = true;
  // Thresholds (issue numbers in the check names' notes).
  double detection_rms_px = 0.15, calibration_rms_px = 0.15;
  double baseline_mm = 0.5, rotation_deg = 0.02, sparse_rel = 0.01;
  double min_psnr_db = 30, dense_median_rel = 0.03;
};

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

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

json ReadJson(const fs::path& p) { return ReadJsonFile(p); }

double Num(const json& j, const std::vector<std::string>& path) {
  const json* x = &j;
  for (const auto& k : path) {
    if (!x->is_object() || !x->contains(k)) return NAN;
    x = &(*x)[k];
  }
  return x->is_number() ? x->get<double>() : NAN;
}

class Validation {
 public:
  // out: the staging folder the stages write into; target: where it goes when the run is complete.
  Validation(Preset p, fs::path out, fs::path target, uint64_t seed, std::string source_dir, bool quiet)
      : p_(std::move(p)), out_(std::move(out)), target_(std::move(target)), seed_(seed), src_(std::move(source_dir)),
        quiet_(quiet) {
    metrics_ = {{"tool", "hovs validate"}, {"versions", Versions()}, {"status", "running"},
                {"config", {{"preset", p_.name}, {"seed", seed_}, {"downscale", p_.downscale},
                            {"mono_frames", p_.mono_count}, {"mono_samples", p_.mono_samples},
                            {"stereo_pairs", p_.stereo_count}, {"stereo_samples", p_.stereo_samples},
                            {"street_samples", p_.street_samples}, {"truth_samples", p_.truth_samples},
                            {"depth", {p_.depth_width, p_.depth_height, p_.disparities}},
                            {"thresholds", {{"detection_rms_px", p_.detection_rms_px},
                                            {"calibration_rms_px", p_.calibration_rms_px},
                                            {"baseline_error_mm", p_.baseline_mm}, {"rotation_error_deg", p_.rotation_deg},
                                            {"sparse_depth_max_rel", p_.sparse_rel}, {"min_view_psnr_db", p_.min_psnr_db},
                                            {"dense_median_rel_1_8m", p_.dense_median_rel}}}}},
                {"stages", json::array()}, {"checks", json::array()}, {"figures", json::object()}};
  }

  std::string Src(const std::string& rel) const { return (fs::path(src_) / rel).string(); }
  std::string Out(const std::string& rel) const { return (out_ / rel).string(); }

  // Runs one stage: its subcommand lines, then the collection of its figures. A failure stops the run.
  void Stage(const std::string& name, const std::vector<std::vector<std::string>>& commands,
             const std::function<void()>& collect = nullptr) {
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

  void Skip(const std::string& name, const std::string& why) {
    metrics_["stages"].push_back({{"name", name}, {"status", "not run"}, {"reason", why}, {"seconds", 0}});
    if (!quiet_) std::fprintf(stderr, "[validate] %s: not run (%s)\n", name.c_str(), why.c_str());
  }

  // A figure compared with its threshold; kind "max" (value <= limit) or "min" (value >= limit). A gate must
  // pass (the run exits 1 otherwise, and CI asserts it); a target is an issue's goal that hovs does not meet yet:
  // measured and shown as met / not met, so the gap stays visible.
  void Check(const std::string& name, double value, const std::string& kind, double limit, const std::string& unit,
             const std::string& source, bool gate = true) {
    const bool pass = std::isfinite(value) && (kind == "max" ? value <= limit : value >= limit);
    metrics_["checks"].push_back({{"name", name}, {"value", std::isfinite(value) ? json(value) : json()},
                                  {"limit", limit}, {"kind", kind}, {"unit", unit}, {"pass", pass},
                                  {"gate", gate}, {"source", source}});
  }

  void Figure(const std::string& key, const json& value) { metrics_["figures"][key] = value; }

  int Failed() const {
    int n = 0;
    for (const auto& c : metrics_["checks"]) n += c["gate"].get<bool>() && !c["pass"].get<bool>();
    return n;
  }

  void Finish(double seconds) {
    int missed = 0;
    for (const auto& c : metrics_["checks"]) missed += !c["gate"].get<bool>() && !c["pass"].get<bool>();
    metrics_["status"] = (Failed() ? "complete, " + std::to_string(Failed()) + " gates FAILED" : "complete, all gates pass") +
                         (missed ? ", " + std::to_string(missed) + " targets not met yet" : std::string());
    metrics_["seconds"] = seconds;
    Write();
    WriteFileAtomic(out_ / "summary.txt", Summary());
  }

  const json& metrics() const { return metrics_; }

  // Text as it reads in the finished report: every path in the staging folder named in the target folder.
  std::string Displayed(std::string text) const {
    const std::string staging = out_.string(), target = target_.string();
    for (size_t at = text.find(staging); at != std::string::npos; at = text.find(staging, at + target.size()))
      text.replace(at, staging.size(), target);
    return text;
  }

  std::string Summary() const {
    std::string s = "hovs validate (" + p_.name + "): " + metrics_["status"].get<std::string>() + " -> " +
                    (target_ / "report.html").string() + "\n";
    for (const auto& c : metrics_["checks"]) {
      const std::string v = c["value"].is_null() ? "n/a" : Fmt("%.4g", c["value"].get<double>());
      const bool gate = c["gate"].get<bool>(), pass = c["pass"].get<bool>();
      s += std::string(gate ? (pass ? "  ok       " : "  FAIL     ") : (pass ? "  met      " : "  not met  ")) +
           c["name"].get<std::string>() + (gate ? "" : " [target]") + ": " + v +
           " " + c["unit"].get<std::string>() + " (" + (c["kind"] == "max" ? "<= " : ">= ") +
           Fmt("%.4g", c["limit"].get<double>()) + ")\n";
    }
    for (const auto& st : metrics_["stages"])
      s += "  stage " + st["name"].get<std::string>() + ": " + st["status"].get<std::string>() + ", " +
           Fmt("%.1f s", st["seconds"].get<double>()) + "\n";
    return s;
  }

 private:

  static double Seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  void Write() const {
    WriteFileAtomic(out_ / "metrics.json", metrics_.dump(1) + "\n");
    WriteFileAtomic(out_ / "report.html", Report());
  }

  std::string Report() const;

  Preset p_;
  fs::path out_, target_;
  uint64_t seed_;
  std::string src_;
  bool quiet_;
  json metrics_;
};

std::string Validation::Report() const {
  const json& m = metrics_;
  results::HtmlPage page("hovs validate: " + p_.name);
  page.Paragraph("Status: " + m["status"].get<std::string>() + ". Every figure below is measured against the "
                 "renderer's ground truth (synthetic stages) or reported as is (real images). Command and versions at "
                 "the end; metrics.json holds every figure.");
  page.Heading("Checks");
  std::vector<std::vector<std::string>> rows;
  for (const auto& c : m["checks"])
    rows.push_back({c["name"], c["value"].is_null() ? "n/a" : Fmt("%.4g", c["value"].get<double>()),
                    std::string(c["kind"] == "max" ? "<= " : ">= ") + Fmt("%.4g", c["limit"].get<double>()),
                    c["unit"], c["gate"].get<bool>() ? "gate" : "target",
                    c["gate"].get<bool>() ? (c["pass"].get<bool>() ? "pass" : "FAIL")
                                          : (c["pass"].get<bool>() ? "met" : "not met yet"),
                    c["source"]});
  page.Table({"check", "value", "threshold", "unit", "kind", "result", "from"}, rows);
  page.Paragraph("Gates must pass (hovs validate exits 1 otherwise; CI runs the reduced preset). Targets are goals "
                 "of the issues that hovs does not reach yet; they are measured on every run so the gap stays visible.");
  page.Heading("Stages and timing");
  rows.clear();
  for (const auto& st : m["stages"])
    rows.push_back({st["name"], st["status"], Fmt("%.1f", st["seconds"].get<double>()),
                    st.contains("error") ? st["error"].get<std::string>()
                                         : st.contains("reason") ? st["reason"].get<std::string>() : ""});
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
      rows.push_back({unit, std::to_string(c["boards_found"].get<int>()) + " / " + std::to_string(c["images"].get<int>()),
                      Fmt("%.4f", c["detection_rms_px"].get<double>()), Fmt("%.4f", c["rms_px"].get<double>()),
                      Fmt("%.5f", c["mean_ray_angle_deg"].get<double>()), Fmt("%.5f", c["max_ray_angle_deg"].get<double>()),
                      Fmt("%.5f", c["mean_ray_angle_aligned_deg"].get<double>()),
                      Fmt("%.4f", c["frame_rotation_deg"].get<double>()),
                      Fmt("%.4f", c["physical_rms_px"].get<double>()), Fmt("%.5f", c["physical_mean_ray_angle_deg"].get<double>()),
                      Fmt("%.4f", c["physical_tilt_error_deg"].get<double>()), Fmt("%.3f", c["physical_centre_error_mm"].get<double>())});
    page.Table({"unit", "boards found", "detection RMS vs exact corners (px)", "polynomial RMS (px)",
                "polynomial: mean ray angle vs true rig (deg)", "max (deg)", "mean, frame rotation removed (deg)",
                "frame rotation (deg)", "physical RMS (px)", "physical: mean ray angle (deg)", "physical: tilt error (deg)",
                "physical: camera centre error (mm)"}, rows);
    page.Paragraph("The later stages use each unit's physical model (mirror at its design a, b; camera tilt and offset "
                   "calibrated; camera intrinsics held at the camera's own calibration, here its design values).");
    fig("data/mono-left/thumbs/left_0000.png", "a rendered calibration image (left unit)", 360);
    fig("calib-left/figures/left_0000.png", "detection and reprojection, left unit (residuals x20)", 420);
    fig("calib-right/figures/right_0000.png", "detection and reprojection, right unit (residuals x20)", 420);
    fig("data/mono-right/thumbs/right_0000.png", "a rendered calibration image (right unit, misaligned)", 360);
  }
  if (f.contains("stereo")) {
    page.Heading("Stereo calibration and sparse depth");
    page.Paragraph("With the exact models (the calibration alone):");
    page.Preformatted(f.value("stereo_exact_models", json()).dump(1));
    page.Paragraph("With the two units' calibrated polynomial models (the whole chain):");
    page.Preformatted(f["stereo"].dump(1));
    for (const auto& e : fs::directory_iterator(fs::exists(out_ / "stereo" / "figures") ? out_ / "stereo" / "figures" : out_)) {
      if (e.path().extension() != ".png") continue;
      fig("stereo/figures/" + e.path().filename().string(), "reprojection: " + e.path().stem().string(), 420);
      break;
    }
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
    fig("panorama/" + f["views"].value("panorama", std::string("none")), "cylindrical panorama (calibrated model)", 900);
  }
  if (f.contains("depth")) {
    page.Heading("Dense depth (calibrated models and pose) against the range channel");
    rows.clear();
    for (const auto& b : f["depth"]["bands"])
      rows.push_back({Fmt("%.0f", b["band_m"][0].get<double>()) + "-" + Fmt("%.0f", b["band_m"][1].get<double>()),
                      std::to_string(b["pixels"].get<int>()), Fmt("%.1f %%", 100 * b["valid_fraction"].get<double>()),
                      b["median_relative_error"].is_null() ? "n/a" : Fmt("%.2f %%", 100 * b["median_relative_error"].get<double>()),
                      Fmt("%.1f %%", 100 * b["within_5_percent_fraction"].get<double>())});
    page.Table({"band (m)", "pixels", "valid", "median rel. error", "within 5 % (of all)"}, rows);
    page.Paragraph("Dense matching time: " + Fmt("%.0f ms", f["depth"]["dense_ms"].get<double>()));
    fig("depth/rectified_left.png", "left unit rectified around the baseline", 900);
    fig("depth/error_map.png", "relative error, 0 (blue) to 5 % or more (red); black: masked", 900);
  }
  if (f.contains("real")) {
    page.Heading("Real images (../shared/data/vmr): no ground truth");
    page.Paragraph("Checked: detection on every image, calibration residuals, the same corners through OpenCV's "
                   "omnidir. Not checkable without ground truth: ray accuracy, the detector's absolute error.");
    page.Preformatted(f["real"].dump(1));
    fig("real/calib/figures/VMRImage0.png", "VMRImage0: detected corners and reprojection (residuals x20)", 420);
    fig("real/panorama/VMRImage0/panorama.png", "panorama of VMRImage0 with the calibrated model", 900);
  }
  page.Heading("Configuration and versions");
  page.Preformatted(json({{"config", m["config"]}, {"versions", m["versions"]}}).dump(1));
  return page.Render();
}

}  // namespace

Runner SetupValidate(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string preset = "full", out, source = ".", real = "../shared/data/vmr";
    uint64_t seed = 1;
    int downscale = 0, mono_frames = 0, stereo_pairs = 0, samples = 0;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--preset", o->preset, "full (the report's run, about 10 min) | reduced (half resolution, CI)")
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "run folder (default results/validate-<preset>)");
  sub->add_option("--seed", o->seed, "seed of board poses and renders")->check(Bounded(0, 9007199254740992.0))->capture_default_str();
  // Each override, when given, must be valid (0 does not mean "the preset").
  sub->add_option("--downscale", o->downscale, "override the preset: render at 1/N resolution (1, 2, 5, 10)")
      ->check(Bounded(1, 16));
  sub->add_option("--mono-frames", o->mono_frames, "override the preset: calibration images per unit")
      ->check(Bounded(1, 10000));
  sub->add_option("--stereo-pairs", o->stereo_pairs, "override the preset: ArUco stereo pairs")
      ->check(Bounded(1, 10000));
  sub->add_option("--samples", o->samples, "override the preset: samples per pixel of every render")
      ->check(Bounded(1, 4096));
  sub->add_option("--source", o->source, "hovs source tree (scenes/, design/)")->capture_default_str();
  sub->add_option("--real", o->real, "folder of real calibration images (7x6 corners, 30 mm); empty: skip")
      ->capture_default_str();
  return [o, global]() {
    Preset p = MakePreset(o->preset);
    if (o->downscale > 0) p.downscale = o->downscale;
    if (o->mono_frames > 0) p.mono_count = o->mono_frames;
    if (o->stereo_pairs > 0) p.stereo_count = o->stereo_pairs;
    if (o->samples > 0) p.mono_samples = p.stereo_samples = p.street_samples = p.truth_samples = o->samples;
    const fs::path target = o->out.empty() ? fs::path("results") / ("validate-" + p.name) : fs::path(o->out);
    for (const char* f : {"scenes/reference_stereo.yaml", "scenes/street.yaml", "design/reference.yaml"})
      HOVS_REQUIRE(fs::exists(fs::path(o->source) / f), "--source", "no ", f, " under '", o->source,
                   "' (run from the source tree or give --source)");
    // Staged like every report: a failed or interrupted run leaves an earlier report as it was.
    StagedDirectory stage(target, "validate", {o->source, o->real});
    const fs::path out = stage.staging();
    const auto t0 = std::chrono::steady_clock::now();
    Validation v(p, out, target, o->seed, o->source, global->quiet);
    const std::string seed = std::to_string(o->seed), ds = std::to_string(p.downscale);
    const std::string stereo_scene = v.Src("scenes/reference_stereo.yaml"), street = v.Src("scenes/street.yaml");

    if (p.design && results::CanRender()) {
      v.Stage("design study", {{"design", "--config", v.Src("design/reference.yaml"), "--out", v.Out("design")}}, [&]() {
        v.Figure("design", v.Displayed(ReadFile(out / "design" / "summary.txt")));
      });
    } else {
      v.Skip("design study", p.design ? "no X display for the figures (run under xvfb-run -a)" : "not in this preset");
    }
    v.Stage("render calibration sets, stereo pairs and the street",
            {{"dataset", "--kind", "mono_calibration", "--scene", stereo_scene, "--unit", "left", "--elevation", "-58", "-4", "--count",
              std::to_string(p.mono_count), "--seed", seed, "--samples", std::to_string(p.mono_samples), "--downscale",
              ds, "--out", v.Out("data/mono-left")},
             {"dataset", "--kind", "mono_calibration", "--scene", stereo_scene, "--unit", "right", "--elevation", "-58", "-4", "--count",
              std::to_string(p.mono_count), "--seed", std::to_string(o->seed + 1), "--samples",
              std::to_string(p.mono_samples), "--downscale", ds, "--out", v.Out("data/mono-right")},
             {"dataset", "--kind", "stereo_aruco", "--scene", stereo_scene, "--count", std::to_string(p.stereo_count),
              "--seed", seed, "--samples", std::to_string(p.stereo_samples), "--downscale", ds, "--out",
              v.Out("data/stereo")},
             {"render", "--scene", street, "--samples", std::to_string(p.street_samples), "--seed", seed,
              "--downscale", ds, "--out", v.Out("data/street")}});

    json calib = json::object();
    for (const std::string unit : {"left", "right"}) {
      v.Stage("detect + calibrate " + unit + " unit",
              {{"calibrate", "--dataset", v.Out("data/mono-" + unit + "/dataset.json"), "--unit", unit, "--physical",
                "--out", v.Out("calib-" + unit)}},
              [&]() {
                const json c = ReadJson(out / ("calib-" + unit) / "calibration.json");
                int found = 0, from_edges = 0;
                for (const auto& d : c["detection"]) found += d["found"].get<bool>(), from_edges += d["from_edges"].get<int>();
                calib[unit] = {{"images", c["detection"].size()}, {"boards_found", found},
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
                        "issue 4: never drop an image");
                v.Check(unit + ": detection RMS vs exact corners", Num(c, {"detection_rms_to_truth_px"}), "max",
                        p.detection_rms_px, "px", "issue 3/4");
                v.Check(unit + ": calibration RMS", Num(c, {"polynomial", "rms_px"}), "max", p.calibration_rms_px, "px",
                        "issue 4");
                v.Check(unit + ": physical model, tilt error", Num(c, {"physical", "ground_truth", "tilt_error_deg"}),
                        "max", 0.05, "deg", "issue 4", p.downscale == 1);
                v.Check(unit + ": physical model (boards + rim), mean ray angle vs true rig",
                        Num(c, {"physical", "ground_truth", "mean_ray_angle_deg"}), "max", 0.01 * p.downscale, "deg",
                        "issue 4 (0.01 deg)", p.downscale == 1);
                // The 0.01 deg is for the aligned rig: a misaligned unit is not single-viewpoint and the
                // polynomial (central) model cannot represent it (its figure is reported above).
                bool single_viewpoint = false;
                const json manifest = ReadJson(out / "data" / ("mono-" + unit) / "dataset.json");
                for (const auto& u : manifest["units"])
                  if (u["name"] == unit) single_viewpoint = u.value("single_viewpoint", false);
                if (single_viewpoint)
                  v.Check(unit + ": polynomial, mean ray angle vs true rig (frame rotation removed)",
                          Num(c, {"ground_truth", "mean_ray_angle_aligned_deg"}), "max", 0.01 * p.downscale, "deg",
                          "issue 4 (0.01 deg, aligned rig)", false);
              });
    }
    const std::string lm = v.Out("calib-left/calibration.json"), rm = v.Out("calib-right/calibration.json");
    v.Stage("stereo calibration, exact models",
            {{"stereo-calibrate", "--dataset", v.Out("data/stereo/dataset.json"), "--out", v.Out("stereo-exact")}},
            [&]() {
              const json s = ReadJson(out / "stereo-exact" / "stereo.json");
              v.Figure("stereo_exact_models", {{"baseline_m", s["baseline_m"]}, {"sigma_baseline_m", s["sigma_baseline_m"]},
                                               {"rms_px", s["rms_px"]}, {"ground_truth", s.value("ground_truth", json())},
                                               {"sparse_depth", s.value("sparse_depth", json())}});
              // Gates at full resolution. At half resolution the markers, unwrapped from a 1375 x 1100 image, are
              // found less precisely (2.5 mm, 4.7 % worst corner in the reduced run): measured, not gated.
              const bool gate = p.downscale == 1;
              v.Check("stereo (exact models): |baseline error|", std::abs(Num(s, {"ground_truth", "baseline_error_mm"})),
                      "max", p.baseline_mm, "mm", "issue 6", gate);
              v.Check("stereo (exact models): rotation error", Num(s, {"ground_truth", "rotation_error_deg"}), "max",
                      p.rotation_deg, "deg", "issue 6", gate);
              // Issue 6's 0.5 % was met on projected corners with 0.05 px noise; detected marker corners (about
              // 0.25 px) triangulated at 3-5 m do not reach it yet: a target.
              v.Check("sparse depth (exact models): 95th percentile relative error",
                      Num(s, {"sparse_depth", "p95_rel_error"}), "max", 0.005, "", "issue 6", false);
              v.Check("sparse depth (exact models): worst relative error", Num(s, {"sparse_depth", "max_rel_error"}),
                      "max", 0.005, "", "issue 6", false);
              // The worst corners lie within 15 deg of the baseline direction (ill-conditioned, like the dense
              // mask): the same figure without them.
              v.Check("sparse depth (exact models), >= 15 deg from the baseline: worst relative error",
                      Num(s, {"sparse_depth", "conditioned", "max_rel_error"}), "max", 0.005, "", "issue 6", false);
            });
    v.Stage("stereo calibration + sparse depth, calibrated physical models",
            {{"stereo-calibrate", "--dataset", v.Out("data/stereo/dataset.json"), "--left-model", lm, "--right-model", rm,
              "--out", v.Out("stereo")}},
            [&]() {
              const json s = ReadJson(out / "stereo" / "stereo.json");
              v.Figure("stereo", {{"baseline_m", s["baseline_m"]}, {"sigma_baseline_m", s["sigma_baseline_m"]},
                                  {"rms_px", s["rms_px"]}, {"ground_truth", s.value("ground_truth", json())},
                                  {"sparse_depth", s.value("sparse_depth", json())},
                                  {"outliers", s["outliers"]["dropped"].size()}});
              // The calibrated frames are the physical models' mirror frames, so the true rig is the reference.
              v.Check("stereo (calibrated models): |baseline error|",
                      std::abs(Num(s, {"ground_truth", "baseline_error_mm"})), "max", p.baseline_mm, "mm", "issue 6",
                      false);
              v.Check("stereo (calibrated models): rotation error", Num(s, {"ground_truth", "rotation_error_deg"}),
                      "max", p.rotation_deg, "deg", "issue 6", false);
              v.Check("sparse depth (calibrated models): 95th percentile relative error",
                      Num(s, {"sparse_depth", "p95_rel_error"}), "max", p.sparse_rel, "", "issue 6", false);
              v.Check("sparse depth (calibrated models): worst relative error",
                      Num(s, {"sparse_depth", "max_rel_error"}), "max", p.sparse_rel, "", "issue 6", false);
              v.Check("sparse depth (calibrated models), >= 15 deg from the baseline: worst relative error",
                      Num(s, {"sparse_depth", "conditioned", "max_rel_error"}), "max", p.sparse_rel, "", "issue 6", false);
            });
    v.Stage("six views + panorama (calibrated left unit)",
            {{"unwrap", "--model", lm, "--unit", "left", "--layout", "article", "--input",
              v.Out("data/street/dataset.json"), "--truth-scene", street, "--truth-samples",
              std::to_string(p.truth_samples), "--out", v.Out("views")},
             {"unwrap", "--model", lm, "--unit", "left", "--layout", "panorama", "--input",
              v.Out("data/street/dataset.json"), "--out", v.Out("panorama")}},
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
              v.Figure("views", {{"psnr_db", psnr}, {"files", files}, {"panorama", pano},
                                 {"median_remap_ms", j["timing"]["median_remap_ms"]}});
              // A regression guard: the street's fine texture at the views' scale, through the calibrated model.
              v.Check("views: worst PSNR against truth renders", worst, "min", p.min_psnr_db, "dB", "issue 5 (guard)");
            });
    v.Stage("dense depth (calibrated models and pose)",
            {{"depth", "--dataset", v.Out("data/street/dataset.json"), "--stereo", v.Out("stereo/stereo.json"),
              "--left-model", lm, "--right-model", rm, "--width", std::to_string(p.depth_width), "--height",
              std::to_string(p.depth_height), "--num-disparities", std::to_string(p.disparities), "--out",
              v.Out("depth")}},
            [&]() {
              const json d = ReadJson(out / "depth" / "depth.json");
              v.Figure("depth", {{"bands", d["ground_truth"]["bands"]}, {"dense_ms", d["timing_ms"]["dense_total"]}});
              double worst = 0;
              for (const auto& b : d["ground_truth"]["bands"])
                if (b["band_m"][1].get<double>() <= 8 && !b["median_relative_error"].is_null())
                  worst = std::max(worst, b["median_relative_error"].get<double>());
              // Issue 6 asks for the table, not a bound: a regression guard on the calibrated chain.
              v.Check("dense depth: worst median relative error, 1-8 m", worst, "max", p.dense_median_rel, "",
                      "issue 6 (guard)");
            });
    if (!o->real.empty() && p.real && fs::is_directory(o->real)) {
      v.Stage("real images: detect + calibrate + panorama",
              {{"calibrate", "--images", o->real, "--board", "7x6x0.03", "--compare-omnidir", "--out",
                v.Out("real/calib")},
               {"unwrap", "--model", v.Out("real/calib/calib_results.txt"), "--layout", "panorama", "--input",
                (fs::path(o->real) / "VMRImage0.jpg").string(), "--out", v.Out("real/panorama")}},
              [&]() {
                const json c = ReadJson(out / "real" / "calib" / "calibration.json");
                int found = 0, from_edges = 0;
                for (const auto& d : c["detection"]) found += d["found"].get<bool>(), from_edges += d["from_edges"].get<int>();
                v.Figure("real", {{"images", c["detection"].size()}, {"boards_found", found},
                                  {"corners_from_edges", from_edges},
                                  {"polynomial_rms_px", Num(c, {"polynomial", "rms_px"})},
                                  {"unified_rms_px", Num(c, {"unified", "rms_px"})},
                                  {"opencv_omnidir_rms_px", Num(c, {"opencv_omnidir", "rms_px"})},
                                  {"target_rms_px", 0.30}});
                v.Check("real: boards found", found, "min", static_cast<double>(c["detection"].size()), "images",
                        "issue 4");
                v.Check("real: calibration RMS, polynomial model", Num(c, {"polynomial", "rms_px"}), "max", 0.30, "px",
                        "issue 4", false);
                v.Check("real: calibration RMS, unified model", Num(c, {"unified", "rms_px"}), "max", 0.30, "px",
                        "issue 4", false);
              });
    } else if (p.real) {
      v.Skip("real images", "no folder '" + o->real + "'");
    } else {
      v.Skip("real images", "not in this preset");
    }
    v.Finish(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    stage.Commit();
    if (global->json) std::cout << v.metrics().dump(1) << "\n";
    else if (!global->quiet) std::cout << v.Summary();
    return v.Failed() ? 1 : 0;
  };
}

}  // namespace hovs::apps
