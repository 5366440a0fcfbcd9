#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "apps/commands.h"
#include "calib/mono_calibration.h"
#include "core/error.h"
#include "design/study.h"
#include "results/plot.h"
#include "scenes/dataset.h"
#include "scenes/scene_config.h"
#include "study/tolerance.h"

namespace hovs::apps {

namespace {

// --truth and --truth-compression: what the dataset writers store of a frame's per-pixel ground truth.
struct TruthOptions {
  std::string channels, compression;
  void Add(CLI::App* sub) {
    sub->add_option("--truth", channels,
                    "ground-truth channels in the EXR: default (Z,N,id,mask), all (adds P and M), none (no EXR; the "
                    "JSON sidecar stays), or a list of Z,P,N,id,mask,M (overrides the scene)");
    sub->add_option("--truth-compression", compression,
                    "the EXR's lossless compression: piz (default), zip, zips, rle, none (overrides the scene)");
  }
  void Apply(raytrace::RenderOptions* r) const {
    if (!channels.empty()) r->truth_file.groups = raytrace::TruthFileOptions::ParseGroups(channels, "--truth");
    if (!compression.empty()) {
      r->truth_file.compression = compression;
      r->truth_file.Check("--truth-compression");
    }
  }
};

}  // namespace

Runner SetupRender(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string scene = "scenes/reference_board.yaml";
    std::string out = "results/render";
    int samples = 0;
    long long seed = -1;
    int downscale = 1;
    TruthOptions truth;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("-s,--scene", o->scene, "scene file (YAML)")->capture_default_str();
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  CLI::Option* samples =
      sub->add_option("--samples", o->samples, "samples per pixel (overrides the scene)")->check(Bounded(1, 4096));
  sub->add_option("--seed", o->seed, "render seed (overrides the scene)")->check(Bounded(0, 9007199254740992.0));
  AddBounded(sub, "--downscale", &o->downscale, "same optics at 1/N of the resolution (quick runs)", 1, 100);
  o->truth.Add(sub);
  return [o, global, samples]() {
    scenes::SceneConfig cfg = scenes::LoadSceneConfig(o->scene);
    scenes::DownscaleCameras(&cfg, o->downscale);
    if (samples->count() > 0) cfg.render.samples = o->samples;
    if (o->seed >= 0) cfg.render.seed = static_cast<uint64_t>(o->seed);
    o->truth.Apply(&cfg.render);
    cfg.render.Check("--samples/--seed");
    scenes::RenderSceneFolder(cfg, o->out, !global->quiet, Versions());
    if (!global->quiet) std::cout << "hovs render: " << cfg.name << " -> " << o->out << "/dataset.json\n";
    return 0;
  };
}

Runner SetupMerge(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::vector<std::string> shards;
    std::string out = "results/dataset";
  };
  auto o = std::make_shared<Options>();
  sub->add_option("SHARDS", o->shards,
                  "the shard folders of one dataset or tolerance study (hovs dataset|tolerance --shard I/N)")
      ->required();
  sub->add_option("-o,--out", o->out, "merged folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    std::vector<std::filesystem::path> dirs(o->shards.begin(), o->shards.end());
    std::string what = "/dataset.json";
    if (study::IsToleranceFolder(dirs.front())) {
      for (const auto& w : study::MergeToleranceShards(dirs, o->out)) std::cerr << "hovs merge: warning: " << w << "\n";
      what = "/tolerance.json";
    } else if (design::IsDesignShard(dirs.front())) {
      HOVS_REQUIRE(results::CanRender(), "hovs merge",
                   "the design report's figures need an X display and DISPLAY is unset; run under `xvfb-run -a`");
      design::MergeDesignShards(dirs, o->out);
      what = "/design.json";
    } else {
      scenes::MergeDatasetShards(dirs, o->out);
    }
    if (!global->quiet) std::cout << "hovs merge: " << dirs.size() << " shards -> " << o->out << what << "\n";
    return 0;
  };
}

Runner SetupDataset(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string scene = "scenes/reference_calibration.yaml";
    std::string out = "results/dataset";
    std::string kind = "mono_calibration";
    double step = 0.5, heading = 0, yaw_step = 0;
    int count = 0;
    uint64_t seed = 1;
    int samples = 0;
    int downscale = 1;
    std::string unit;
    std::vector<double> elevation, distance;
    std::string board, shard;
    bool resume = false;
    TruthOptions truth;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("-s,--scene", o->scene, "base scene: units, background (its boards are replaced)")
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  sub->add_option("--kind", o->kind, "mono_calibration | stereo_aruco | depth_sequence")->capture_default_str();
  AddBounded(sub, "--step", &o->step, "depth_sequence: rig motion per frame, m", -100, 100);
  AddBounded(sub, "--heading", &o->heading, "depth_sequence: direction of motion, degrees from world +x towards +y",
             -360, 360);
  AddBounded(sub, "--yaw-step", &o->yaw_step, "depth_sequence: rig turn per frame about the vertical, degrees", -90,
             90);
  CLI::Option* count =
      sub->add_option("-n,--count", o->count, "frames (default: 9 mono, 12 stereo)")->check(Bounded(1, 10000));
  AddBounded(sub, "--seed", &o->seed, "seed of the board poses", 0, 9007199254740992.0);
  CLI::Option* samples =
      sub->add_option("--samples", o->samples, "samples per pixel (overrides the scene)")->check(Bounded(1, 4096));
  AddBounded(sub, "--downscale", &o->downscale, "same optics at 1/N of the resolution (quick runs)", 1, 100);
  sub->add_option("--unit", o->unit, "mono_calibration: the unit to calibrate (default: the scene's first)");
  sub->add_option("--elevation", o->elevation, "board centre elevation range MIN MAX, degrees (default: per kind)")
      ->check(Bounded(-90, 90))
      ->expected(2);
  sub->add_option("--distance", o->distance, "board centre distance range MIN MAX, m (default: per kind)")
      ->check(Bounded(0.01, 1000))
      ->expected(2);
  sub->add_option("--board", o->board,
                  "mono_calibration: checkerboard COLSxROWSxSQUARE, inner corners and square (m), e.g. 7x11x0.03, or "
                  "charuco:SXxSYxSQUARExMARKER[:DICTIONARY] (squares; sides in m), e.g. charuco:8x12x0.03x0.022");
  sub->add_flag("--resume", o->resume,
                "continue a killed run of the same command (its whole frames kept); with it, an interrupt keeps the "
                "run for the next --resume");
  sub->add_option("--shard", o->shard,
                  "I/N: render shard I (from 0) of N of the set (hovs merge joins them); default: from "
                  "SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT when Slurm sets them");
  o->truth.Add(sub);
  return [o, global, samples, count]() {
    scenes::SceneConfig cfg = scenes::LoadSceneConfig(o->scene);
    scenes::DownscaleCameras(&cfg, o->downscale);
    if (!o->unit.empty()) scenes::SelectUnit(&cfg, o->unit);
    if (samples->count() > 0) cfg.render.samples = o->samples;
    o->truth.Apply(&cfg.render);
    cfg.render.Check("--samples");
    scenes::DatasetOptions d = scenes::DatasetOptions::ForKind(o->kind);
    if (count->count() > 0) d.count = o->count;
    if (!o->elevation.empty()) d.min_elevation_deg = o->elevation[0], d.max_elevation_deg = o->elevation[1];
    if (!o->distance.empty()) d.min_distance = o->distance[0], d.max_distance = o->distance[1];
    if (!o->board.empty()) {
      HOVS_REQUIRE(d.kind == "mono_calibration", "--board", "sets the board of a mono_calibration dataset");
      if (o->board.rfind("charuco:", 0) == 0) {
        const calib::CharucoSpec c = calib::ParseCharucoSpec(o->board, "--board");
        d.board.kind = scenes::BoardSpec::Kind::kCharuco;
        d.board.squares_x = c.squares_x, d.board.squares_y = c.squares_y, d.board.square = c.square;
        d.board.marker_length = c.marker, d.board.dictionary = c.dictionary;
      } else {
        const calib::CheckerboardSpec spec = calib::ParseBoardSpec(o->board, "--board");
        d.board.kind = scenes::BoardSpec::Kind::kChecker;
        d.board.squares_x = spec.cols + 1, d.board.squares_y = spec.rows + 1, d.board.square = spec.square;
      }
    }
    ParseShard(o->shard, &d.shard_index, &d.shard_count);
    d.Check("dataset options");
    d.seed = o->seed;
    d.progress = !global->quiet;
    d.resume = o->resume;
    d.step_m = o->step, d.heading_deg = o->heading, d.yaw_step_deg = o->yaw_step;
    if (d.kind == "depth_sequence")
      scenes::WriteDepthSequence(cfg, d, o->out, Versions());
    else
      scenes::WriteCalibrationDataset(cfg, d, o->out, Versions());
    if (!global->quiet)
      std::cout << "hovs dataset: " << d.count << " frames (" << d.kind << ") -> " << o->out << "/dataset.json\n";
    return 0;
  };
}

}  // namespace hovs::apps
