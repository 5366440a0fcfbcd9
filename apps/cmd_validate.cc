// hovs validate: the whole chain on the reference design, every stage against ground truth, one report.
//
//   design study -> renders (a monocular calibration set per unit of the binocular rig, ArUco stereo pairs, the
//   street scene) -> checkerboard detection + monocular calibration of both units -> stereo calibration with the
//   calibrated models (+ sparse depth of the marker corners) -> six-view expansion and panorama of the street with
//   the calibrated model, against pinhole renders -> dense depth of the street with the calibrated models and pose,
//   against the range channel -> the real images of ../shared/data/vmr (detection, calibration beside OpenCV's
//   omnidir, a panorama; no ground truth there) -> the variable-scale unit: each turret mirror calibrated where the
//   positioning loop put it, a round of switches checked on fresh boards, the same round in one live stream.
//
// Each stage runs the same code as its subcommand (in process, through the command table) and writes into
// <out>/<stage folder>; metrics.json and report.html are rewritten after every stage, so a run stopped by bad
// input leaves valid partial results that say they are partial and which stage failed. Checks compare figures
// with the thresholds of the issues (scaled for the reduced preset, which renders at half resolution).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/validation.h"
#include "core/error.h"
#include "core/io.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

}  // namespace

Runner SetupValidate(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string preset = "full", out, source = ".", real = "../shared/data/vmr";
    uint64_t seed = 1;
    int downscale = 0, mono_frames = 0, stereo_pairs = 0, samples = 0;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--preset", o->preset,
                  "full (the report's run, 12-15 min on 2 cores) | reduced (half resolution, CI)")
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "run folder (default results/validate-<preset>)");
  AddBounded(sub, "--seed", &o->seed, "seed of board poses and renders", 0, 9007199254740992.0);
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
    for (const char* f :
         {"scenes/reference_stereo.yaml", "scenes/street.yaml", "design/reference.yaml", "scenes/turret.yaml"})
      HOVS_REQUIRE(fs::exists(fs::path(o->source) / f), "--source", "no ", f, " under '", o->source,
                   "' (run from the source tree or give --source)");
    // Staged like every report: a failed or interrupted run leaves an earlier report as it was.
    StagedDirectory stage(target, "validate", {o->source, o->real});
    const auto t0 = std::chrono::steady_clock::now();
    Validation v(p, stage.staging(), target, o->seed, o->source, global->quiet);
    DesignAndRenders(v, o->seed);
    MonoCalibrations(v);
    StereoCalibrations(v);
    ViewsAndDenseDepth(v);
    RealImages(v, o->real);
    VariableScale(v, o->seed);
    v.Finish(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    stage.Commit();
    if (global->json)
      std::cout << v.metrics().dump(1) << "\n";
    else if (!global->quiet)
      std::cout << v.Summary();
    return v.Failed() ? 1 : 0;
  };
}

}  // namespace hovs::apps
