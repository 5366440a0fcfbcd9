// hovs live: frames from a camera (or the simulator, or a replay) expanded into the views of a layout as they
// arrive — a raw BayerRG8 frame goes straight to RGB views (demosaiced inside the remap) — shown on the display
// (--display), written (--out, every Nth frame) or both, with per-stage latency figures (live.json).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <iostream>
#include <optional>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/commands.h"
#include "apps/live_depth.h"
#include "apps/live_publish.h"
#include "apps/live_rig.h"
#include "apps/model_files.h"
#include "apps/sources.h"
#include "apps/unwrap_rig.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/io.h"
#include "core/statistics.h"
#include "hw/live.h"
#include "unwrap/layout.h"
#include "unwrap/remap.h"
#include "unwrap/remap_table.h"
#include "unwrap/rig_mapping.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;
struct LiveCommandOptions {
  SourceOptions source;
  RigLiveCliOptions rig;
  PublishCliOptions publish;
  LiveDepthCliOptions depth;
  double pair_tolerance_ms = 2;
  std::string model, unit, map, layout = "article", interp = "bilinear", out;
  int frames = 100, write_every = 0;
  double seconds = 0, timeout = 3, scene_distance = 10;
  bool display = false, fixed_elevation = false;
};

nlohmann::json Latency(const std::vector<double>& v) {
  if (v.empty()) return nlohmann::json();
  const SampleSummary s = Summarise(v);
  return {{"median_ms", s.median}, {"p95_ms", s.p95}, {"max_ms", s.max}, {"mean_ms", s.mean}, {"frames", s.count}};
}

// A mosaic of the views, three per row, scaled to 1800 px wide at most; q or Esc sets *stop.
void ShowMosaic(const std::vector<unwrap::Image8>& views, std::atomic<bool>* stop) {
  const int cols = std::min<int>(3, static_cast<int>(views.size()));
  const int rows = (static_cast<int>(views.size()) + cols - 1) / cols;
  const int cw = views[0].width, ch = views[0].height;
  cv::Mat mosaic(rows * ch, cols * cw, CV_8UC3, cv::Scalar(0, 0, 0));
  for (size_t v = 0; v < views.size(); ++v) {
    if (views[v].width != cw || views[v].height != ch) continue;
    cv::Mat m(ch, cw, views[v].channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<uint8_t*>(views[v].data.data()));
    cv::Mat bgr;
    cv::cvtColor(m, bgr, views[v].channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_GRAY2BGR);
    bgr.copyTo(mosaic(cv::Rect(static_cast<int>(v % cols) * cw, static_cast<int>(v / cols) * ch, cw, ch)));
  }
  const double scale = std::min(1.0, 1800.0 / mosaic.cols);
  if (scale < 1) cv::resize(mosaic, mosaic, cv::Size(), scale, scale, cv::INTER_AREA);
  cv::imshow("hovs live", mosaic);
  const int key = cv::waitKey(1);
  if (key == 'q' || key == 27) stop->store(true);
}

// What hovs live expands: one unit's table, or a rig mapping of two units; the views' specs in output order.
struct LiveMapping {
  std::optional<unwrap::RemapTable> table;
  std::optional<unwrap::RigMapping> rig;
  std::vector<unwrap::ViewSpec> specs;
  explicit LiveMapping(unwrap::RemapTable t) : table(std::move(t)) {
    for (const auto& v : table->views) specs.push_back(v.spec);
  }
  explicit LiveMapping(unwrap::RigMapping m) : rig(std::move(m)) {
    for (int k = 0; k < rig->ViewCount(); ++k) specs.push_back(rig->View(k).spec);
  }
};

unwrap::RemapTable UnitLiveMapping(const LiveCommandOptions& o) {
  if (!o.map.empty()) return unwrap::LoadRemapTable(o.map);
  const AnyModel model = LoadModelSpec(o.model, o.unit, o.scene_distance);
  return unwrap::BuildRemapTable(model, unwrap::ResolveLayout(o.layout, o.fixed_elevation ? nullptr : &model),
                                 unwrap::RemapOptions(), nlohmann::json(Versions()).dump());
}

unwrap::RigMapping RigLiveMapping(const LiveCommandOptions& o) {
  if (!o.map.empty()) return unwrap::LoadRigMapping(o.map);
  const std::vector<unwrap::RigUnitModel> units = LoadRigUnits(o.model, o.scene_distance);
  const unwrap::Layout layout = unwrap::ResolveLayout(o.layout, o.fixed_elevation ? nullptr : &units[0].model);
  unwrap::RigMapping m =
      unwrap::BuildRigMapping(units, layout, unwrap::RemapOptions(), nlohmann::json(Versions()).dump());
  HOVS_REQUIRE(m.units.size() == 2, "--layout " + o.layout, "hovs live expands pairs: the layout's views must come ",
               "from two units (they come from ", m.units.size(), ")");
  return m;
}

void CheckOptions(const LiveCommandOptions& o) {
  HOVS_REQUIRE(o.model.empty() != o.map.empty(), "hovs live", "give either --model or --map");
  HOVS_REQUIRE(o.frames > 0 || o.seconds > 0 || o.display, "hovs live",
               "give --frames or --seconds (or --display, ended with q)");
  HOVS_REQUIRE(o.write_every == 0 || !o.out.empty(), "--write-every", "needs --out");
  HOVS_REQUIRE(!o.display || std::getenv("DISPLAY"), "--display", "no display (DISPLAY is unset)");
  HOVS_REQUIRE(o.source.pixel_format != "Mono16", "--pixel-format",
               "live expansion takes Mono8 or BayerRG8 frames (Mono16 is for capture)");
}

// live.json's common part: the sources, the figures and the latencies of every stage.
nlohmann::json LiveJson(const LiveCommandOptions& o, const std::vector<hw::CameraSource*>& cams, size_t views,
                        double table_ms, const hw::LiveRun& r, const nlohmann::json& published,
                        uint64_t* underruns_out) {
  const bool pair = cams.size() == 2;
  nlohmann::json sources = nlohmann::json::array(), streams = nlohmann::json::array();
  uint64_t underruns = 0;
  for (auto* c : cams) {
    sources.push_back(c->Info());
    streams.push_back(c->Stats().ToJson());
    underruns += c->Stats().underruns;
  }
  nlohmann::json j = {{"tool", "hovs live"},
                      {"versions", Versions()},
                      {"source", pair ? sources : sources[0]},
                      {"pixel_format", o.source.pixel_format},
                      {"views", views},
                      {"interpolation", o.interp},
                      {"mapping_ms", table_ms},
                      {"frames_processed", r.processed},
                      {"frames_incomplete", r.incomplete},
                      {"frames_written", r.written},
                      {"seconds", r.seconds},
                      {"fps", r.processed / std::max(r.seconds, 1e-9)},
                      {"stream", pair ? streams : streams[0]},
                      {"dds", published},
                      {"latency",
                       {{"wait_for_frame", Latency(r.wait_ms)},
                        {"remap", Latency(r.remap_ms)},
                        {"write", Latency(r.write_ms)},
                        {"display", Latency(r.display_ms)},
                        {"publish", Latency(r.sink_ms)},
                        {"frame_to_output", Latency(r.total_ms)}}},
                      {"note",
                       "remap: all views of one frame (of a pair: both frames in one pass), TBB threads; "
                       "wait_for_frame includes the camera's frame period"}};
  *underruns_out = underruns;
  return j;
}

int RunLiveCommand(const LiveCommandOptions& o, const GlobalOptions& global) {
  if (!o.rig.rig_json.empty()) {
    HOVS_REQUIRE(o.model.empty() && o.map.empty(), "--rig",
                 "the rig folder gives each mirror's mapping; drop --model / --map");
    HOVS_REQUIRE(o.source.cameras.empty() && o.source.replay.empty(), "--rig",
                 "the unit runs in simulation (--simulate MACHINE.yaml)");
    HOVS_REQUIRE(!o.display, "--rig", "--display is not available with a rig yet");
    HOVS_REQUIRE(!o.publish.publish, "--publish", "not available with --rig yet");
    return RunRigLiveCommand(o.rig, {o.source.simulate, o.out, o.interp, o.frames, o.write_every, Versions()}, global);
  }
  HOVS_REQUIRE(o.rig.switches.empty() && o.rig.start.empty(), "--switch", "needs --rig");
  CheckOptions(o);
  hw::LiveOptions lo;
  lo.interpolation = unwrap::ParseInterpolation(o.interp);
  std::optional<stream::DdsOptions> dds = o.publish.Resolve();
  if (dds && !o.source.replay.empty())  // a replay has no deadline: every frame reaches every reader
    dds->history = 0, dds->max_blocking_s = 5;
  const std::optional<depth::LiveDepthOptions> depth_options = o.depth.Resolve();
  // One unit's views (a table), or a rig layout's views of two units (a rig mapping) expanded from frame pairs.
  const bool pair = IsRigUnwrap(o.layout, o.map);
  const auto tb = std::chrono::steady_clock::now();
  const LiveMapping mapping = pair ? LiveMapping(RigLiveMapping(o)) : LiveMapping(UnitLiveMapping(o));
  const double table_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tb).count();
  OpenedSources src = OpenSources(o.source);
  const std::vector<hw::CameraSource*> cams =
      pair ? PairSources(src, mapping.rig->units) : std::vector<hw::CameraSource*>{src.sources[0].get()};
  // The output folder is staged like a report and committed when the run ends (its frame count, Ctrl-C or
  // q); an error leaves an earlier output as it was.
  std::optional<StagedDirectory> staged;
  if (!o.out.empty()) staged.emplace(o.out, "live");
  lo.frames = o.frames, lo.seconds = o.seconds, lo.timeout = o.timeout, lo.write_every = o.write_every;
  lo.out_dir = staged ? staged->staging() : fs::path();
  lo.software_trigger = o.source.trigger == "software";
  lo.replay = !o.source.replay.empty();
  lo.source_name = !o.source.simulate.empty() ? "--simulate " + o.source.simulate
                   : !o.source.replay.empty() ? "--replay " + o.source.replay
                                              : "--camera " + o.source.cameras.front();
  lo.mapping_name = o.map.empty() ? o.model : o.map;
  lo.format = o.source.pixel_format == "BayerRG8" ? unwrap::PixelFormat::kBayerRggb8 : unwrap::PixelFormat::kGray8;
  std::atomic<bool> stop{false};
  const InterruptScope interrupt(&stop);  // Ctrl-C ends the run with its figures; a second one ends the process
  std::function<void(const std::vector<unwrap::Image8>&)> display;
  if (o.display) display = [&](const std::vector<unwrap::Image8>& views) { ShowMosaic(views, &stop); };
  // Published frames: the views are swapped into the publisher (no copy) and an older frame's come back. A
  // replay has no deadline, so it waits for the publisher instead of dropping frames.
  const std::unique_ptr<stream::Publisher> publisher = OpenPublisher(o.publish, dds, mapping.specs);
  stream::Bundle bundle;
  hw::LiveSink sink;
  if (publisher)
    sink = [&](uint64_t stamp_ns, std::vector<unwrap::Image8>* views) {
      bundle.stamp_ns = stamp_ns;
      bundle.images.swap(*views);
      publisher->Offer(&bundle, lo.replay);
      bundle.images.swap(*views);
    };
  nlohmann::json pairs, depth_json;
  hw::LiveRun r;
  if (pair) {
    std::unique_ptr<LiveDepthOutput> depth;
    if (depth_options) {
      HOVS_REQUIRE(!o.model.empty(), "--depth", "needs --model (a scene YAML or dataset manifest: the units' poses)");
      depth = std::make_unique<LiveDepthOutput>(
          LoadStereoRig(o.model, mapping.rig->units[0], mapping.rig->units[1], o.scene_distance, o.depth.stereo),
          *depth_options, dds, o.publish.prefix);
    }
    const hw::PairLiveRun pr =
        hw::RunPairLive(cams, *mapping.rig, lo, &stop, display, sink, static_cast<uint64_t>(o.pair_tolerance_ms * 1e6),
                        depth ? depth->Sink() : hw::PairFramesSink());
    r = pr.live;
    if (depth) depth_json = depth->Finish(lo.out_dir, r.seconds);
    pairs = {{"units", mapping.rig->units},
             {"unpaired_frames", pr.unpaired},
             {"dropped_pairs", pr.dropped_pairs},
             {"skew", Latency(pr.skew_ms)},
             {"tolerance_ms", o.pair_tolerance_ms},
             {"note", "unpaired: frames whose partner never came within the tolerance, never expanded alone"}};
  } else {
    HOVS_REQUIRE(!depth_options, "--depth", "needs frame pairs: a two-unit layout such as --layout binocular");
    r = hw::RunLive(*cams[0], *mapping.table, lo, &stop, display, sink);
  }
  nlohmann::json published;
  if (publisher) {
    publisher->Flush(5);
    published = {{"topics", publisher->Topics()}, {"frames", publisher->Stats().ToJson()}};
  }
  uint64_t underruns = 0;
  nlohmann::json j = LiveJson(o, cams, mapping.specs.size(), table_ms, r, published, &underruns);
  if (pair) j["pairs"] = pairs;
  if (!depth_json.is_null()) j["depth"] = depth_json;
  if (staged) {
    WriteFileAtomic(lo.out_dir / "live.json", j.dump(1) + "\n");
    staged->Commit();
  }
  if (global.json) {
    std::cout << j.dump(1) << "\n";
  } else if (!global.quiet) {
    std::printf(
        "hovs live: %d frames in %.1f s (%.1f fps), %d incomplete, %llu stream underruns; median remap "
        "%.1f ms, frame-to-output %.1f ms\n",
        r.processed, r.seconds, r.processed / std::max(r.seconds, 1e-9), r.incomplete,
        static_cast<unsigned long long>(underruns), Summarise(r.remap_ms).median, Summarise(r.total_ms).median);
  }
  return 0;
}

}  // namespace

Runner SetupLive(CLI::App* sub, const GlobalOptions* global) {
  auto o = std::make_shared<LiveCommandOptions>();
  AddSourceOptions(sub, &o->source);
  AddRigLiveOptions(sub, &o->rig);
  AddPublishOptions(sub, &o->publish);
  AddLiveDepthOptions(sub, &o->depth);
  AddBounded(sub, "--pair-tolerance-ms", &o->pair_tolerance_ms,
             "frame pairs: the largest difference of the two device timestamps (hardware trigger: 2 ms; free-running "
             "cameras: half the frame period)",
             0, 1e4);
  sub->add_option("--model", o->model, "model: scene YAML, dataset.json, calib_results.txt or calibration.json");
  sub->add_option("--unit", o->unit, "unit of a scene or manifest model");
  sub->add_option("--map", o->map, "a mapping file (hovs unwrap --save-map) instead of --model");
  sub->add_option("--layout", o->layout, "article | panorama | longlat | binocular (frame pairs) | layout YAML")
      ->capture_default_str();
  sub->add_flag("--fixed-elevation", o->fixed_elevation,
                "presets keep their fixed elevations instead of following the model's field");
  sub->add_option("--interp", o->interp, "bilinear | bicubic | nearest")->capture_default_str();
  AddBounded(sub, "-n,--frames", &o->frames, "frames to process (0: until Ctrl-C or --seconds)", 0, 1e9);
  AddBounded(sub, "--seconds", &o->seconds, "stop after this long (0: no limit)", 0, 1e7);
  AddBounded(sub, "--timeout", &o->timeout, "seconds to wait for a frame", 0, 3600, true);
  sub->add_flag("--display", o->display, "show the views (needs a display; q or Esc ends)");
  sub->add_option("-o,--out", o->out, "folder for live.json and written views");
  AddBounded(sub, "--write-every", &o->write_every, "write the views of every Nth frame (0: never)", 0, 1e9);
  return [o, global]() { return RunLiveCommand(*o, *global); };
}

}  // namespace hovs::apps
