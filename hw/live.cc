#include "hw/live.h"

#include <chrono>
#include <cstdio>

#include "core/error.h"
#include "io/image_io.h"

namespace hovs::hw {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

void Loop(CameraSource& cam, const unwrap::RemapTable& table, const LiveOptions& o, std::atomic<bool>* stop,
          const std::function<void(const std::vector<unwrap::Image8>&)>& display, const LiveSink& sink, LiveRun* r) {
  unwrap::Remapper remapper(table);
  std::vector<unwrap::Image8> views;
  const auto t_start = Clock::now();
  // Every wait is bounded overall: a frame must be processed within the timeout of the previous one (or of the
  // start), whatever the source delivers meanwhile (incomplete frames).
  auto last_progress = Clock::now();
  while (!stop->load()) {
    HOVS_REQUIRE(Ms(last_progress, Clock::now()) <= 1e3 * o.timeout, "hovs live", "no complete frame within ",
                 o.timeout, " s (", r->incomplete, " incomplete frames; --timeout sets the wait)");
    if (o.frames > 0 && r->processed >= o.frames) break;
    if (o.seconds > 0 && Ms(t_start, Clock::now()) > 1e3 * o.seconds) break;
    if (o.software_trigger) cam.SoftwareTrigger();
    const auto t0 = Clock::now();
    auto f = cam.Grab(o.timeout);
    const auto t1 = Clock::now();
    const uint64_t stamp_ns = static_cast<uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
            .count());
    if (!f) {
      HOVS_REQUIRE(o.replay || stop->load(), "hovs live", "no frame within ", o.timeout, " s (timeout)");
      break;  // the replay ended
    }
    if (!f->complete) {
      ++r->incomplete;
      continue;
    }
    HOVS_REQUIRE(f->width == table.source_width && f->height == table.source_height, o.source_name, "the frames are ",
                 f->width, " x ", f->height, " but the mapping (", o.mapping_name, ") is for ", table.source_width,
                 " x ", table.source_height);
    remapper.Run({f->data.data(), f->width, f->height, size_t(f->width), o.format}, o.interpolation, &views);
    const auto t2 = Clock::now();
    if (o.write_every > 0 && r->processed % o.write_every == 0) {
      char stem[32];
      std::snprintf(stem, sizeof stem, "frame%06d", r->processed);
      WriteLiveViews(o.out_dir, stem, table, views);
      ++r->written;
    }
    const auto t3 = Clock::now();
    if (display) display(views);
    const auto t4 = Clock::now();
    if (sink) sink(stamp_ns, &views);
    const auto t5 = Clock::now();
    if (sink) r->sink_ms.push_back(Ms(t4, t5));
    r->wait_ms.push_back(Ms(t0, t1)), r->remap_ms.push_back(Ms(t1, t2));
    if (o.write_every > 0) r->write_ms.push_back(Ms(t2, t3));
    if (display) r->display_ms.push_back(Ms(t3, t4));
    r->total_ms.push_back(Ms(t1, t5));
    ++r->processed;
    last_progress = Clock::now();
  }
  r->seconds = Ms(t_start, Clock::now()) / 1e3;
}

}  // namespace

void WriteNamedViews(const std::filesystem::path& dir, const std::string& stem, const std::vector<std::string>& names,
                     const std::vector<unwrap::Image8>& views) {
  for (size_t v = 0; v < views.size(); ++v) {
    std::vector<float> fl(views[v].data.size());
    for (size_t k = 0; k < fl.size(); ++k) fl[k] = views[v].data[k] / 255.f;
    io::WriteImage(dir / (stem + "_" + names[v] + ".png"), views[v].width, views[v].height, views[v].channels, fl, 8);
  }
}

void WriteLiveViews(const std::filesystem::path& dir, const std::string& stem, const unwrap::RemapTable& table,
                    const std::vector<unwrap::Image8>& views) {
  std::vector<std::string> names;
  for (const auto& v : table.views) names.push_back(v.spec.name);
  WriteNamedViews(dir, stem, names, views);
}

LiveRun RunLive(CameraSource& cam, const unwrap::RemapTable& table, const LiveOptions& options, std::atomic<bool>* stop,
                const std::function<void(const std::vector<unwrap::Image8>&)>& display, const LiveSink& sink) {
  LiveRun r;
  cam.Start();
  try {
    Loop(cam, table, options, stop, display, sink, &r);
  } catch (...) {
    cam.Stop();
    throw;
  }
  cam.Stop();
  return r;
}

}  // namespace hovs::hw
