// hovs live: frames from a camera (or the simulator, or a replay) expanded into the views of a layout as they
// arrive — a raw BayerRG8 frame goes straight to RGB views (demosaiced inside the remap) — shown on the display
// (--display), written (--out, every Nth frame) or both, with per-stage latency figures (live.json).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "apps/sources.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/io.h"
#include "raytrace/render.h"
#include "unwrap/layout.h"
#include "unwrap/remap.h"
#include "unwrap/remap_table.h"
#include "io/image_io.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

nlohmann::json Stats(std::vector<double> v) {
  if (v.empty()) return nlohmann::json();
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  return {{"median_ms", v[v.size() / 2]}, {"p95_ms", v[std::min(v.size() - 1, v.size() * 95 / 100)]},
          {"max_ms", v.back()}, {"mean_ms", sum / v.size()}, {"frames", v.size()}};
}

}  // namespace

Runner SetupLive(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    SourceOptions source;
    std::string model, unit, map, layout = "article", interp = "bilinear", out;
    int frames = 100, write_every = 0;
    double seconds = 0, timeout = 3, scene_distance = 10;
    bool display = false;
  };
  auto o = std::make_shared<Options>();
  AddSourceOptions(sub, &o->source);
  sub->add_option("--model", o->model, "model: scene YAML, dataset.json, calib_results.txt or calibration.json");
  sub->add_option("--unit", o->unit, "unit of a scene or manifest model");
  sub->add_option("--map", o->map, "a mapping file (hovs unwrap --save-map) instead of --model");
  sub->add_option("--layout", o->layout, "article | panorama | longlat | layout YAML")->capture_default_str();
  sub->add_option("--interp", o->interp, "bilinear | bicubic | nearest")->capture_default_str();
  sub->add_option("-n,--frames", o->frames, "frames to process (0: until Ctrl-C or --seconds)")->check(Bounded(0, 1e9))->capture_default_str();
  sub->add_option("--seconds", o->seconds, "stop after this long (0: no limit)")->check(Bounded(0, 1e7))->capture_default_str();
  sub->add_option("--timeout", o->timeout, "seconds to wait for a frame")->check(Bounded(0, 3600, true))->capture_default_str();
  sub->add_flag("--display", o->display, "show the views (needs a display; q or Esc ends)");
  sub->add_option("-o,--out", o->out, "folder for live.json and written views");
  sub->add_option("--write-every", o->write_every, "write the views of every Nth frame (0: never)")->check(Bounded(0, 1e9))
      ->capture_default_str();
  return [o, global]() {
    HOVS_REQUIRE(o->model.empty() != o->map.empty(), "hovs live", "give either --model or --map");
    HOVS_REQUIRE(o->frames >= 0 && o->write_every >= 0 && o->seconds >= 0, "hovs live",
                 "--frames, --write-every and --seconds must not be negative");
    HOVS_REQUIRE(std::isfinite(o->timeout) && o->timeout > 0 && o->timeout <= 3600, "--timeout",
                 "must be in (0, 3600] seconds (got ", o->timeout, ")");
    HOVS_REQUIRE(o->frames > 0 || o->seconds > 0 || o->display, "hovs live",
                 "give --frames or --seconds (or --display, ended with q)");
    HOVS_REQUIRE(o->write_every == 0 || !o->out.empty(), "--write-every", "needs --out");
    HOVS_REQUIRE(!o->display || std::getenv("DISPLAY"), "--display", "no display (DISPLAY is unset)");
    HOVS_REQUIRE(o->source.pixel_format != "Mono16", "--pixel-format",
                 "live expansion takes Mono8 or BayerRG8 frames (Mono16 is for capture)");
    const unwrap::Interpolation interp = unwrap::ParseInterpolation(o->interp);
    const auto tb = Clock::now();
    const unwrap::RemapTable table =
        o->map.empty() ? unwrap::BuildRemapTable(LoadModelSpec(o->model, o->unit, o->scene_distance),
                                                 unwrap::ResolveLayout(o->layout), unwrap::RemapOptions(),
                                                 nlohmann::json(Versions()).dump())
                       : unwrap::LoadRemapTable(o->map);
    const double table_ms = Ms(tb, Clock::now());
    OpenedSources src = OpenSources(o->source);
    hw::CameraSource& cam = *src.sources[0];
    // The output folder is staged like a report and committed when the run ends (its frame count, Ctrl-C or
    // q); an error leaves an earlier output as it was.
    std::optional<StagedDirectory> staged;
    if (!o->out.empty()) staged.emplace(o->out, "live");
    const fs::path out_dir = staged ? staged->staging() : fs::path();
    unwrap::Remapper remapper(table);
    const unwrap::PixelFormat fmt =
        o->source.pixel_format == "BayerRG8" ? unwrap::PixelFormat::kBayerRggb8 : unwrap::PixelFormat::kGray8;
    std::vector<double> wait_ms, remap_ms, write_ms, display_ms, total_ms;
    int processed = 0, incomplete = 0, written = 0;
    std::atomic<bool> stop{false};
    const InterruptScope interrupt(&stop);   // Ctrl-C ends the run with its figures; a second one ends the process
    cam.Start();
    const auto t_start = Clock::now();
    std::vector<unwrap::Image8> views;
    try {
      // Every wait is bounded overall: a frame must be processed within --timeout of the previous one (or of the
      // start), whatever the source delivers meanwhile (incomplete frames).
      auto last_progress = Clock::now();
      while (!stop.load()) {
        HOVS_REQUIRE(Ms(last_progress, Clock::now()) <= 1e3 * o->timeout, "hovs live", "no complete frame within ",
                     o->timeout, " s (", incomplete, " incomplete frames; --timeout sets the wait)");
        if (o->frames > 0 && processed >= o->frames) break;
        if (o->seconds > 0 && Ms(t_start, Clock::now()) > 1e3 * o->seconds) break;
        if (o->source.trigger == "software") cam.SoftwareTrigger();
        const auto t0 = Clock::now();
        auto f = cam.Grab(o->timeout);
        const auto t1 = Clock::now();
        if (!f) {
          HOVS_REQUIRE(!o->source.replay.empty() || stop.load(), "hovs live", "no frame within ",
                       o->timeout, " s (timeout)");
          break;  // the replay ended
        }
        if (!f->complete) {
          ++incomplete;
          continue;
        }
        HOVS_REQUIRE(f->width == table.source_width && f->height == table.source_height,
                     !o->source.simulate.empty() ? "--simulate " + o->source.simulate
                     : !o->source.replay.empty() ? "--replay " + o->source.replay
                                                 : "--camera " + o->source.cameras.front(),
                     "the frames are ", f->width, " x ", f->height, " but the mapping (", o->map.empty() ? o->model : o->map,
                     ") is for ", table.source_width, " x ", table.source_height);
        remapper.Run({f->data.data(), f->width, f->height, size_t(f->width), fmt}, interp, &views);
        const auto t2 = Clock::now();
        if (o->write_every > 0 && processed % o->write_every == 0) {
          for (size_t v = 0; v < views.size(); ++v) {
            std::vector<float> fl(views[v].data.size());
            for (size_t k = 0; k < fl.size(); ++k) fl[k] = views[v].data[k] / 255.f;
            char rel[160];
            std::snprintf(rel, sizeof rel, "frame%06d_%s.png", processed, table.views[v].spec.name.c_str());
            io::WriteImage(out_dir / rel, views[v].width, views[v].height, views[v].channels, fl, 8);
          }
          ++written;
        }
        const auto t3 = Clock::now();
        if (o->display) {
          // A mosaic of the views, three per row, scaled to 1800 px wide at most.
          const int cols = std::min<int>(3, static_cast<int>(views.size()));
          const int rows = (static_cast<int>(views.size()) + cols - 1) / cols;
          const int cw = views[0].width, ch = views[0].height;
          cv::Mat mosaic(rows * ch, cols * cw, CV_8UC3, cv::Scalar(0, 0, 0));
          for (size_t v = 0; v < views.size(); ++v) {
            if (views[v].width != cw || views[v].height != ch) continue;
            cv::Mat m(ch, cw, views[v].channels == 3 ? CV_8UC3 : CV_8UC1, views[v].data.data());
            cv::Mat bgr;
            if (views[v].channels == 3) cv::cvtColor(m, bgr, cv::COLOR_RGB2BGR); else cv::cvtColor(m, bgr, cv::COLOR_GRAY2BGR);
            bgr.copyTo(mosaic(cv::Rect(static_cast<int>(v % cols) * cw, static_cast<int>(v / cols) * ch, cw, ch)));
          }
          const double scale = std::min(1.0, 1800.0 / mosaic.cols);
          if (scale < 1) cv::resize(mosaic, mosaic, cv::Size(), scale, scale, cv::INTER_AREA);
          cv::imshow("hovs live", mosaic);
          const int key = cv::waitKey(1);
          if (key == 'q' || key == 27) stop.store(true);
        }
        const auto t4 = Clock::now();
        wait_ms.push_back(Ms(t0, t1)), remap_ms.push_back(Ms(t1, t2));
        if (o->write_every > 0) write_ms.push_back(Ms(t2, t3));
        if (o->display) display_ms.push_back(Ms(t3, t4));
        total_ms.push_back(Ms(t1, t4));
        ++processed;
        last_progress = Clock::now();
      }
    } catch (...) {
      cam.Stop();
      throw;
    }
    cam.Stop();
    const double wall = Ms(t_start, Clock::now()) / 1e3;
    const auto stats = cam.Stats();
    nlohmann::json j = {{"tool", "hovs live"}, {"versions", Versions()},
                        {"source", cam.Info()}, {"pixel_format", o->source.pixel_format},
                        {"views", table.views.size()}, {"interpolation", o->interp}, {"mapping_ms", table_ms},
                        {"frames_processed", processed}, {"frames_incomplete", incomplete}, {"frames_written", written},
                        {"seconds", wall}, {"fps", processed / std::max(wall, 1e-9)},
                        {"stream", stats.ToJson()},
                        {"latency", {{"wait_for_frame", Stats(wait_ms)}, {"remap", Stats(remap_ms)},
                                     {"write", Stats(write_ms)}, {"display", Stats(display_ms)},
                                     {"frame_to_output", Stats(total_ms)}}},
                        {"note", "remap: all views of one frame, TBB threads; wait_for_frame includes the camera's "
                                 "frame period"}};
    if (staged) {
      WriteFileAtomic(out_dir / "live.json", j.dump(1) + "\n");
      staged->Commit();
    }
    if (global->json) {
      std::cout << j.dump(1) << "\n";
    } else if (!global->quiet) {
      const auto med = [&](const char* k) {
        return j["latency"][k].is_null() ? 0.0 : j["latency"][k]["median_ms"].get<double>();
      };
      std::printf("hovs live: %d frames in %.1f s (%.1f fps), %d incomplete, %llu stream underruns; median remap "
                  "%.1f ms, frame-to-output %.1f ms\n",
                  processed, wall, processed / std::max(wall, 1e-9), incomplete,
                  static_cast<unsigned long long>(stats.underruns), med("remap"), med("frame_to_output"));
    }
    return 0;
  };
}

}  // namespace hovs::apps
