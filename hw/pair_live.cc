// The live loop over two units: a grabbing thread per source feeds the pairer; the pipeline expands pairs.
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "core/error.h"
#include "hw/live.h"

namespace hovs::hw {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

struct Shared {
  std::mutex mutex;
  std::condition_variable cv;
  FramePairer pairer;
  std::deque<std::pair<Frame, Frame>> pairs;
  int incomplete = 0;
  uint64_t dropped_pairs = 0;
  int ended = 0;  // sources whose replay ended
  bool done = false;
  std::exception_ptr error;
};

void Grabber(CameraSource* cam, int stream, const LiveOptions& o, Shared* sh) {
  try {
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(sh->mutex);
        if (sh->done) return;
      }
      if (o.software_trigger) cam->SoftwareTrigger();
      auto f = cam->Grab(std::min(0.2, o.timeout));
      std::unique_lock<std::mutex> lock(sh->mutex);
      if (!f) {
        if (o.replay && !o.software_trigger) {
          ++sh->ended;
          sh->cv.notify_all();
          return;
        }
        continue;  // the pipeline's own timeout decides when waiting has lasted too long
      }
      if (!f->complete) {
        ++sh->incomplete;
        continue;
      }
      for (auto& p : sh->pairer.Add(stream, std::move(*f))) {
        if (o.replay) {
          sh->cv.wait(lock, [&] { return sh->pairs.size() < 2 || sh->done; });
        } else if (sh->pairs.size() >= 2) {
          sh->pairs.pop_front();
          ++sh->dropped_pairs;
        }
        sh->pairs.push_back(std::move(p));
      }
      sh->cv.notify_all();
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(sh->mutex);
    sh->error = std::current_exception();
    sh->done = true;
    sh->cv.notify_all();
  }
}

unwrap::PixelFormat FormatOf(const Frame& f, unwrap::PixelFormat configured) {
  return f.pixel_format == "BayerRG8" ? unwrap::PixelFormat::kBayerRggb8
         : f.pixel_format == "Mono8"  ? unwrap::PixelFormat::kGray8
                                      : configured;
}

}  // namespace

void WriteRigLiveViews(const std::filesystem::path& dir, const std::string& stem, const unwrap::RigMapping& mapping,
                       const std::vector<unwrap::Image8>& views) {
  std::vector<std::string> names;
  for (int k = 0; k < mapping.ViewCount(); ++k) names.push_back(mapping.View(k).spec.name);
  WriteNamedViews(dir, stem, names, views);
}

PairLiveRun RunPairLive(const std::vector<CameraSource*>& cams, const unwrap::RigMapping& mapping, const LiveOptions& o,
                        std::atomic<bool>* stop, const std::function<void(const std::vector<unwrap::Image8>&)>& display,
                        const LiveSink& sink, uint64_t pair_tolerance_ns, const PairFramesSink& frames_sink) {
  HOVS_REQUIRE(cams.size() == 2 && mapping.units.size() == 2, o.source_name,
               "a pair needs two sources and a mapping of ", "two units (got ", cams.size(), " sources, ",
               mapping.units.size(), " units)");
  PairLiveRun run;
  LiveRun& r = run.live;
  Shared sh;
  sh.pairer.tolerance_ns = pair_tolerance_ns;
  for (auto* c : cams) c->Start();
  std::vector<std::thread> threads;
  for (int k = 0; k < 2; ++k) threads.emplace_back(Grabber, cams[k], k, std::cref(o), &sh);
  const auto finish = [&] {
    {
      std::lock_guard<std::mutex> lock(sh.mutex);
      sh.done = true;
    }
    sh.cv.notify_all();
    for (auto& t : threads) t.join();
    for (auto* c : cams) c->Stop();
  };
  try {
    unwrap::RigRemapper remapper(mapping);
    std::vector<unwrap::Image8> views;
    const auto t_start = Clock::now();
    auto last_progress = Clock::now();
    for (;;) {
      if (stop->load()) break;
      if (o.frames > 0 && r.processed >= o.frames) break;
      if (o.seconds > 0 && Ms(t_start, Clock::now()) > 1e3 * o.seconds) break;
      const auto t0 = Clock::now();
      std::unique_lock<std::mutex> lock(sh.mutex);
      sh.cv.wait_for(lock, std::chrono::milliseconds(100),
                     [&] { return !sh.pairs.empty() || sh.error || sh.ended == 2; });
      if (sh.error) std::rethrow_exception(sh.error);
      if (sh.pairs.empty()) {
        if (sh.ended == 2) {  // both replays ended
          HOVS_REQUIRE(r.processed > 0, o.source_name, "no frame pair: no two frames' timestamps are within ",
                       pair_tolerance_ns * 1e-6, " ms (", sh.pairer.dropped, " frames unpaired)");
          break;
        }
        lock.unlock();
        HOVS_REQUIRE(Ms(last_progress, Clock::now()) <= 1e3 * o.timeout, "hovs live", "no complete pair within ",
                     o.timeout, " s (", sh.incomplete, " incomplete frames, ", sh.pairer.dropped,
                     " unpaired; --timeout sets the wait)");
        continue;
      }
      std::pair<Frame, Frame> p = std::move(sh.pairs.front());
      sh.pairs.pop_front();
      sh.cv.notify_all();
      lock.unlock();
      const auto t1 = Clock::now();
      const uint64_t stamp_ns = static_cast<uint64_t>(
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
              .count());
      const Frame* f[2] = {&p.first, &p.second};
      HOVS_REQUIRE(f[0]->pixel_format == f[1]->pixel_format, "unit " + mapping.units[1], "its frames are ",
                   f[1]->pixel_format, " but unit ", mapping.units[0], "'s are ", f[0]->pixel_format,
                   " (a pair needs one pixel format)");
      std::vector<unwrap::ImageView> srcs;
      for (int k = 0; k < 2; ++k)
        srcs.push_back({f[k]->data.data(), f[k]->width, f[k]->height, size_t(f[k]->width), FormatOf(*f[k], o.format)});
      remapper.Run(srcs, o.interpolation, &views);
      const auto t2 = Clock::now();
      if (o.write_every > 0 && r.processed % o.write_every == 0) {
        char stem[32];
        std::snprintf(stem, sizeof stem, "frame%06d", r.processed);
        WriteRigLiveViews(o.out_dir, stem, mapping, views);
        ++r.written;
      }
      const auto t3 = Clock::now();
      if (display) display(views);
      const auto t4 = Clock::now();
      if (sink) sink(stamp_ns, &views);
      const auto t5 = Clock::now();
      r.wait_ms.push_back(Ms(t0, t1)), r.remap_ms.push_back(Ms(t1, t2));
      if (o.write_every > 0) r.write_ms.push_back(Ms(t2, t3));
      if (display) r.display_ms.push_back(Ms(t3, t4));
      if (sink) r.sink_ms.push_back(Ms(t4, t5));
      r.total_ms.push_back(Ms(t1, t5));
      const uint64_t a = f[0]->device_ns, b = f[1]->device_ns;
      run.skew_ms.push_back((a > b ? a - b : b - a) * 1e-6);
      if (frames_sink) frames_sink(stamp_ns, &p.first, &p.second);
      ++r.processed;
      last_progress = Clock::now();
    }
    r.seconds = Ms(t_start, Clock::now()) / 1e3;
  } catch (...) {
    finish();
    throw;
  }
  finish();
  r.incomplete = sh.incomplete;
  run.unpaired = sh.pairer.dropped;
  run.dropped_pairs = sh.dropped_pairs;
  return run;
}

}  // namespace hovs::hw
