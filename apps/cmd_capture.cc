// hovs capture: frames from one or two GigE Vision cameras (Aravis), a replayed folder, or Aravis' GigE Vision
// simulator serving a rendered dataset (--simulate), written as a hovs dataset (dataset.json without ground
// truth, per-frame metadata, stream statistics). Ctrl-C ends the capture with a valid manifest.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "apps/commands.h"
#include "apps/sources.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/io.h"
#include "hw/capture.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;
}  // namespace

Runner SetupCapture(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    SourceOptions source;
    std::string out = "results/capture";
    int frames = 10, write_queue = 16;
    std::string image_format = "png";
    double seconds = 0, timeout = 3, pair_ms = 2;
  };
  auto o = std::make_shared<Options>();
  AddSourceOptions(sub, &o->source);
  AddBounded(sub, "-n,--frames", &o->frames, "frames (pairs) to write", 1, 1e9);
  AddBounded(sub, "--seconds", &o->seconds, "stop after this long (0: no limit)", 0, 1e7);
  AddBounded(sub, "--timeout", &o->timeout, "seconds to wait for a frame", 0, 3600, true);
  AddBounded(sub, "--pair-tolerance-ms", &o->pair_ms, "two cameras: timestamps of a pair differ by at most this", 0,
             10000, true);
  AddBounded(sub, "--write-queue", &o->write_queue, "frames (pairs) grabbed but not yet written, at most", 1, 4096);
  sub->add_option("--image-format", o->image_format,
                  "png (compressed) | pgm (uncompressed, written at disk speed for full frame rates)")
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "dataset folder (must not exist or be empty)")->capture_default_str();
  return [o, global]() {
    // A capture is written where it is going (an interrupted one keeps its frames) and never replaces anything:
    // the folder must be new or empty.
    CheckOutputFolder(o->out, "capture");
    HOVS_REQUIRE(!fs::exists(o->out) || fs::is_empty(o->out), o->out,
                 "the output folder exists and is not empty (captures are never mixed or replaced)");
    HOVS_REQUIRE(std::isfinite(o->pair_ms) && o->pair_ms > 0 && o->pair_ms <= 10000, "--pair-tolerance-ms",
                 "must be in (0, 10000] ms (got ", o->pair_ms, ")");
    // Ctrl-C (or SIGTERM) from here on ends the capture with a valid manifest (one that ends before its first
    // frame leaves nothing, hw/capture.h); a second one ends the process.
    std::atomic<bool> stop{false};
    const InterruptScope interrupt(&stop);
    OpenedSources src = OpenSources(o->source);
    hw::CaptureOptions co;
    co.frames = o->frames, co.max_seconds = o->seconds, co.grab_timeout_s = o->timeout;
    co.pair_tolerance_ns = static_cast<uint64_t>(o->pair_ms * 1e6);
    co.write_queue = o->write_queue, co.image_format = o->image_format;
    // The simulators run at 25 fps on their own clocks: a pair is at most a period apart.
    if (!src.simulators.empty() && src.sources.size() == 2)
      co.pair_tolerance_ns = std::max<uint64_t>(co.pair_tolerance_ns, 20'000'000);
    co.software_trigger = o->source.trigger == "software";
    co.progress = !global->quiet;
    co.unit_names = src.units;
    const hw::CaptureResult r = hw::CaptureDataset(src.Raw(), co, o->out, Versions(), &stop);
    if (global->json) {
      std::cout << r.manifest.dump(1) << "\n";
    } else if (!global->quiet) {
      std::printf(
          "hovs capture: %d frames written, %d incomplete (not written), %llu unpaired%s, writer queue up to "
          "%d -> %s/dataset.json\n",
          r.written, r.incomplete, static_cast<unsigned long long>(r.unpaired), r.interrupted ? ", interrupted" : "",
          r.max_queue_depth, o->out.c_str());
    }
    return 0;
  };
}

}  // namespace hovs::apps
