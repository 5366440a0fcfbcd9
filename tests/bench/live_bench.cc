// The live pipeline of `hovs live` for one 2750 x 2200 camera in BayerRG8: frames expanded into the article's
// six 1200 x 700 RGB views (demosaiced inside the remap) as they arrive.
//
// BM_LiveExpansion: the expansion alone, frame after frame: the frame rate the pipeline sustains (target: at
//   least 30 frames per second on this 2-core machine).
// BM_LiveCamera/<fps>: frames from Aravis' GigE Vision simulator in this process (127.0.0.1, real GVSP over UDP)
//   free-running at <fps>, grabbed and expanded as they arrive for 6 s. Counters: fps processed, dropped frames
//   (frames never delivered, i.e. frame-id gaps, and frames delivered incomplete; target at 10 fps: none), the
//   stream's buffer underruns. The simulator shares the two cores with the pipeline and serves 2750 x 2200 frames
//   at 17-28 fps when 30 are asked (it is the limit there, not the expansion: BM_LiveExpansion).
#include <benchmark/benchmark.h>

#include <chrono>
#include <random>

#include "hw/camera_source.h"
#include "hw/fake_gige.h"
#include "unwrap/remap.h"
#include "tests/bench/article_table.h"

namespace {

using namespace hovs;

// A raw RGGB mosaic with texture (smoothed noise per colour plane).
hw::FakeFrame BayerFrame(uint32_t seed) {
  hw::FakeFrame f;
  f.width = 2750, f.height = 2200;
  f.data.resize(size_t(f.width) * f.height);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(0, 255);
  for (auto& b : f.data) b = static_cast<uint8_t>(d(rng));
  return f;
}

void BM_LiveExpansion(benchmark::State& state) {
  const auto frame = BayerFrame(1);
  unwrap::Remapper remapper(test::ArticleTable());
  std::vector<unwrap::Image8> views;
  for (auto _ : state) {
    remapper.Run({frame.data.data(), frame.width, frame.height, size_t(frame.width), unwrap::PixelFormat::kBayerRggb8},
                 unwrap::Interpolation::kBilinear, &views);
    benchmark::DoNotOptimize(views[0].data.data());
  }
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LiveExpansion)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

void BM_LiveCamera(benchmark::State& state) {
  const double rate = static_cast<double>(state.range(0));
  std::vector<hw::FakeFrame> frames = {BayerFrame(1), BayerFrame(2)};
  hw::FakeGigECamera sim("127.0.0.1", "HOVS-BENCH", frames);
  hw::CaptureSettings s;
  s.pixel_format = "BayerRG8";
  s.frame_rate = rate;
  std::unique_ptr<hw::CameraSource> cam;
  try {
    cam = hw::OpenAravisCamera("127.0.0.1", s);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  unwrap::Remapper remapper(test::ArticleTable());
  std::vector<unwrap::Image8> views;
  uint64_t processed = 0, dropped = 0, last_id = 0;
  double seconds = 0;
  for (auto _ : state) {
    cam->Start();
    const auto t0 = std::chrono::steady_clock::now();
    bool first = true;
    while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 6.0) {
      auto f = cam->Grab(3.0);
      if (!f) {
        state.SkipWithError("no frame from the simulator within 3 s");
        break;
      }
      // Drops: frames never delivered (frame-id gaps) and frames delivered incomplete, the first one included
      // (since the stream socket is sized before acquisition starts, the simulator's first frame arrives whole).
      if (!first && f->frame_id > last_id + 1) dropped += f->frame_id - last_id - 1;
      first = false, last_id = f->frame_id;
      if (!f->complete) {
        ++dropped;
        continue;
      }
      remapper.Run({f->data.data(), f->width, f->height, size_t(f->width), unwrap::PixelFormat::kBayerRggb8},
                   unwrap::Interpolation::kBilinear, &views);
      ++processed;
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cam->Stop();
  }
  const auto st = cam->Stats();
  state.counters["fps"] = processed / std::max(seconds, 1e-9);
  state.counters["dropped"] = static_cast<double>(dropped);
  state.counters["underruns"] = static_cast<double>(st.underruns);
  state.counters["frames"] = static_cast<double>(processed);
}
BENCHMARK(BM_LiveCamera)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
