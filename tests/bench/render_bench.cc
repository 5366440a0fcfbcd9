// Renderer speed: a 2750 x 2200 frame at 4 samples per pixel with ground truth (target: at most 1.5 s on the
// 2-core machine), beside the raw rtcIntersect16 throughput on the same scene and the same kind of rays
// (reflected rays of the same frame), so the renderer's overhead shows as a ratio (target: >= 75 % of raw).
#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <thread>

#include "core/large_pages.h"
#include "raytrace/render.h"
#include "raytrace/texture.h"
#include "scenes/dataset.h"
#include "scenes/scene_config.h"
#include "io/image_io.h"

namespace {

using hovs::Vec2d;
using hovs::Vec3d;

// The renderer's libraries in the report's context, beside what bench_main.cc records (CPU, core versions).
const bool kContext = [] {
  for (const auto& [name, version] : hovs::raytrace::RaytraceVersions()) benchmark::AddCustomContext(name, version);
  return true;
}();

const hovs::scenes::SceneConfig& Scene() {
  static const auto cfg = hovs::scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
  return cfg;
}

void BM_RenderFrame(benchmark::State& state) {
  const hovs::raytrace::RayScene scene(Scene().description);
  hovs::raytrace::RenderOptions ro;
  ro.samples = static_cast<int>(state.range(0));
  ro.ground_truth = state.range(1) != 0;
  uint64_t rays = 0;
  for (auto _ : state) {
    const auto f = hovs::raytrace::Render(scene, hovs::raytrace::ViewCamera::Unit(0), ro);
    rays += f.rays;
    benchmark::DoNotOptimize(f.rgb.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderFrame)->Args({4, 1})->Args({4, 0})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The same frame rendered into reused buffers (RenderInto, as the dataset writer does from its second frame on):
// the frame's memory is already mapped, so this is the steady state of a sequence of frames.
// Frames of unit 0 rendered into one frame's buffers, mapped by a first render before the timing.
void RenderReusedFrames(benchmark::State& state, const hovs::raytrace::RayScene& scene,
                        const hovs::raytrace::RenderOptions& ro) {
  hovs::raytrace::Frame f;
  hovs::raytrace::RenderInto(scene, hovs::raytrace::ViewCamera::Unit(0), ro, &f);  // maps the buffers
  uint64_t rays = 0;
  for (auto _ : state) {
    hovs::raytrace::RenderInto(scene, hovs::raytrace::ViewCamera::Unit(0), ro, &f);
    rays += f.rays;
    benchmark::DoNotOptimize(f.rgb.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}

void BM_RenderFrameReused(benchmark::State& state) {
  const hovs::raytrace::RayScene scene(Scene().description);
  hovs::raytrace::RenderOptions ro;
  ro.samples = static_cast<int>(state.range(0));
  ro.ground_truth = state.range(1) != 0;
  RenderReusedFrames(state, scene, ro);
}
BENCHMARK(BM_RenderFrameReused)
    ->Args({4, 1})
    ->Args({4, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

// The same frame (reused buffers, 4 samples per pixel, ground truth) with the optional camera effects, which take
// the double-precision path: 0 a thin lens (2 mm aperture radius, focused at 1.5 m), 1 the lens and motion blur
// of a unit moving at 1.58 m/s and turning at 30 degrees/s during a 20 ms exposure.
void BM_RenderFrameEffects(benchmark::State& state) {
  hovs::raytrace::SceneDescription d = Scene().description;
  if (state.range(0) == 1) {
    d.units[0].velocity = Vec3d(1.5, 0.5, 0);
    d.units[0].angular_velocity = Vec3d(0, 0, 30 * M_PI / 180);
  }
  const hovs::raytrace::RayScene scene(d);
  hovs::raytrace::RenderOptions ro;
  ro.samples = 4;
  ro.ground_truth = true;
  ro.lens_radius = 0.002;
  ro.focus_distance = 1.5;
  if (state.range(0) == 1) ro.exposure_time = 0.02;
  RenderReusedFrames(state, scene, ro);
}
BENCHMARK(BM_RenderFrameEffects)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The reflected rays of every pixel of the frame (one per pixel), precomputed, for the raw throughput figure:
// in double (o, d) and in single-precision packets of 16 (RayScene::RawPacket16, Embree's own layout).
struct RawRays {
  std::vector<Vec3d> o, d;
  std::vector<hovs::raytrace::RayScene::RawPacket16> packets;
  explicit RawRays(const hovs::raytrace::RayScene& scene) {
    const auto& unit = scene.description().units[0];
    for (int y = 0; y < unit.rig.camera.height; ++y)
      for (int x = 0; x < unit.rig.camera.width; ++x) {
        Vec3d M, dir;
        if (!unit.rig.RayFromImg(Vec2d(x + 0.25, y + 0.25), &M, &dir)) continue;
        o.push_back(unit.world_from_mirror * M);
        d.push_back(unit.world_from_mirror.Rotate(dir));
      }
    packets.resize(o.size() / 16);
    for (size_t p = 0; p < packets.size(); ++p)
      for (int i = 0; i < 16; ++i) {
        const Vec3d &oi = o[16 * p + i], &di = d[16 * p + i];
        auto& k = packets[p];
        k.ox[i] = static_cast<float>(oi.x()), k.oy[i] = static_cast<float>(oi.y()),
        k.oz[i] = static_cast<float>(oi.z());
        k.dx[i] = static_cast<float>(di.x()), k.dy[i] = static_cast<float>(di.y()),
        k.dz[i] = static_cast<float>(di.z());
      }
  }
  size_t Count() const { return packets.size() * 16; }
  // All of them, on both cores: from the single-precision packets with rtcIntersect16 (width 16) or
  // rtcIntersect8 (width 8, what the renderer uses without AVX-512); the raw reference.
  void Trace(const hovs::raytrace::RayScene& scene, int width) const {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, packets.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
      unsigned ids[16];
      for (size_t p = r.begin(); p != r.end(); ++p) scene.IntersectRaw(packets[p], 0, width, ids);
      benchmark::DoNotOptimize(ids[0]);
    });
  }
  // The same rays from double-precision vectors, each lane converted while its packet is filled
  // (RayScene::IntersectOnly16): the raw figure of the measurement of 2026-12-03 (commit 28909e9), which spends about
  // half its time filling.
  void TraceFromDouble(const hovs::raytrace::RayScene& scene) const {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, packets.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
      unsigned ids[16];
      const int from[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
      for (size_t p = r.begin(); p != r.end(); ++p) scene.IntersectOnly16(16, &o[16 * p], &d[16 * p], ids, from);
      benchmark::DoNotOptimize(ids[0]);
    });
  }
};

// Argument: 16 or 8, the packet width from single-precision packets; 0, rtcIntersect16 filled from doubles.
void BM_RawIntersect16(benchmark::State& state) {
  const hovs::raytrace::RayScene scene(Scene().description);
  const RawRays raw(scene);
  const int width = static_cast<int>(state.range(0));
  for (auto _ : state) {
    if (width == 0) {
      raw.TraceFromDouble(scene);
    } else {
      raw.Trace(scene, width);
    }
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(static_cast<double>(raw.Count()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RawIntersect16)->Arg(16)->Arg(8)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(10);

// The ratio in one figure: each iteration renders the frame with ground truth and traces the raw rays five
// times right after, each timed on its own, so that both see the same state of this VM (whose speed drifts by tens
// of per cent within minutes). ratio = the frame's rays per second over raw rtcIntersect16's (from single-precision
// packets), summed over the iterations; ratio_to_raw8 the same over rtcIntersect8's; ratio_to_raw_from_double over
// rtcIntersect16 filled lane by lane from doubles, the reference of the measurement of 2026-12-03 (commit a2b1d88)
// (0.5-0.8 times as fast as the raw figure: its packet filling took about as long as Embree's traversal), kept so that
// their figures can be compared. Argument: the frame's buffers (the first frame, which maps memory new to the process,
// rendered before the timing): 0 fresh ones, the previous frame's freed just before (inside the timing); 1 reused
// (RenderInto); 2 fresh ones, the previous frame's freed right after its render, so about a second before (during the
// raw traces): on a VM whose hypervisor takes back guest memory that stays free (see BM_FrameMemoryFirstTouch) the new
// buffers came through host page faults until freed large buffers were kept for reuse (hovs::KeepFreedLargePages, set
// up by the benchmark main as by the hovs command); now 0 and 2 get the previous frame's memory back.
void RatioToRaw(benchmark::State& state, const hovs::scenes::SceneConfig& config, int mode) {
  const hovs::raytrace::RayScene scene(config.description);
  const RawRays raw(scene);
  hovs::raytrace::RenderOptions ro;
  ro.samples = 4;
  ro.ground_truth = true;
  hovs::raytrace::Frame kept;
  if (mode == 1) hovs::raytrace::RenderInto(scene, hovs::raytrace::ViewCamera::Unit(0), ro, &kept);
  std::optional<hovs::raytrace::Frame> previous;
  if (mode == 0) previous = hovs::raytrace::Render(scene, hovs::raytrace::ViewCamera::Unit(0), ro);
  double frame_s = 0, raw_s = 0, raw8_s = 0, raw_double_s = 0, frame_rays = 0, raw_rays = 0, frame_embree = 0;
  using Clock = std::chrono::steady_clock;
  for (auto _ : state) {
    auto t0 = Clock::now();
    if (mode == 1) {
      hovs::raytrace::RenderInto(scene, hovs::raytrace::ViewCamera::Unit(0), ro, &kept);
      frame_rays += static_cast<double>(kept.rays);
      frame_embree += static_cast<double>(kept.embree_rays);
    } else if (mode == 0) {
      previous.reset();
      previous = hovs::raytrace::Render(scene, hovs::raytrace::ViewCamera::Unit(0), ro);
      frame_rays += static_cast<double>(previous->rays);
      frame_embree += static_cast<double>(previous->embree_rays);
    } else {
      const auto f = hovs::raytrace::Render(scene, hovs::raytrace::ViewCamera::Unit(0), ro);
      frame_rays += static_cast<double>(f.rays);
      frame_embree += static_cast<double>(f.embree_rays);
    }
    frame_s += std::chrono::duration<double>(Clock::now() - t0).count();
    t0 = Clock::now();
    for (int k = 0; k < 5; ++k) raw.Trace(scene, 16);
    raw_s += std::chrono::duration<double>(Clock::now() - t0).count();
    raw_rays += 5.0 * static_cast<double>(raw.Count());
    t0 = Clock::now();
    for (int k = 0; k < 5; ++k) raw.Trace(scene, 8);
    raw8_s += std::chrono::duration<double>(Clock::now() - t0).count();
    t0 = Clock::now();
    for (int k = 0; k < 5; ++k) raw.TraceFromDouble(scene);
    raw_double_s += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  state.counters["frame_rays_per_s"] = frame_rays / frame_s;
  state.counters["raw_rays_per_s"] = raw_rays / raw_s;
  state.counters["ratio"] = (frame_rays / frame_s) / (raw_rays / raw_s);
  // Counted strictly: only the frame's rays that Embree traced (the ratio above also counts the camera rays past the
  // rim, about 37 % of this frame's, which end on the unit's mount ring analytically), over the frame's whole time.
  state.counters["embree_share"] = frame_embree / frame_rays;
  state.counters["ratio_embree_rays"] = (frame_embree / frame_s) / (raw_rays / raw_s);
  // Without AVX-512, rtcIntersect8 (the renderer's packet width there) was the faster raw figure on the machine
  // measured (Zen 3: 37-42 vs 31-36 M rays/s): the ratio to it too, so that such a machine is not judged kindly.
  state.counters["raw8_rays_per_s"] = raw_rays / raw8_s;
  state.counters["ratio_to_raw8"] = (frame_rays / frame_s) / (raw_rays / raw8_s);
  state.counters["raw_from_double_rays_per_s"] = raw_rays / raw_double_s;
  state.counters["ratio_to_raw_from_double"] = (frame_rays / frame_s) / (raw_rays / raw_double_s);
}
void BM_RenderRatioToRaw(benchmark::State& state) { RatioToRaw(state, Scene(), static_cast<int>(state.range(0))); }
BENCHMARK(BM_RenderRatioToRaw)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(4);

// The same figures (reused buffers, unit 0's view) on the other shipped scenes, whose Embree work per ray differs
// from the reference board's (a floor and a board): 0 room.yaml (walls, ceiling, furniture), 1 street.yaml (the
// binocular rig among buildings and boxes: unit 0 also sees unit 1), 2 reference_stereo.yaml.
void BM_RenderRatioToRawScenes(benchmark::State& state) {
  static const char* const kScenes[] = {"room", "street", "reference_stereo"};
  const auto config =
      hovs::scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/" + kScenes[state.range(0)] + ".yaml");
  state.SetLabel(kScenes[state.range(0)]);
  RatioToRaw(state, config, 1);
}
BENCHMARK(BM_RenderRatioToRawScenes)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(4);

// What fresh frame buffers cost by themselves: the 362 MB of a 2750 x 2200 frame with ground truth (PixelBuffers
// in huge pages, as Render allocates them), one write per 4 KiB page from both threads (the render's tiles write
// every byte; the bytes themselves cost the same with reused buffers), then freed. Argument: for how long (ms)
// the freed memory lies unused before the next frame's buffers are allocated (outside the timing). On a
// virtual machine whose hypervisor takes freed guest memory back (free page reporting, as on the Firecracker VMs
// this project is measured on: kernel command line page_reporting.page_reporting_order=11), memory that has been
// free for more than about 1.5 s comes back through host page faults, which BM_RenderRatioToRaw/2 pays every
// frame (its raw traces take about a second between two renders); memory freed a moment ago does not.
void BM_FrameMemoryFirstTouch(benchmark::State& state) {
  // Freed buffers are unmapped here, not kept for reuse (hovs::KeepFreedLargePages): what that saves is measured.
  const size_t keep = hovs::KeepFreedLargePages(0);
  const size_t n = size_t(2750) * 2200 * (3 + hovs::raytrace::GroundTruth::kChannels);
  const auto touch = [n] {
    hovs::raytrace::PixelBuffer b(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, size_t(1) << 20), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); i += 1024) b[i] = 1.0f;
    });
    benchmark::DoNotOptimize(b.data());
  };
  touch();  // the process's first frame-sized touch (memory new to this process) is not what is measured
  for (auto _ : state) {
    state.PauseTiming();
    std::this_thread::sleep_for(std::chrono::milliseconds(state.range(0)));
    state.ResumeTiming();
    touch();
  }
  state.counters["MB"] = static_cast<double>(n * sizeof(float)) / 1e6;
  hovs::KeepFreedLargePages(keep);
}
BENCHMARK(BM_FrameMemoryFirstTouch)->Arg(0)->Arg(2500)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(4);

// The noise texture by itself (about 12 % of a reference frame's profile): the reference floor's texture (5 octaves,
// base cell 0.08 m) at 2^20 single-precision points uniform over 10 x 10 m, in the renderer's runs of 256 points,
// on one core. So a change to the kernel shows apart from the frame's run-to-run spread.
void BM_NoiseTexture(benchmark::State& state) {
  hovs::raytrace::Texture tex;
  tex.kind = hovs::raytrace::Texture::Kind::kNoise;
  tex.scale = 0.08, tex.octaves = 5, tex.seed = 11;
  constexpr int kPoints = 1 << 20, kRun = 256;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-5.0f, 5.0f);
  std::vector<float> s(kPoints), t(kPoints), rgb(3 * kRun);
  for (int i = 0; i < kPoints; ++i) s[i] = pos(rng), t[i] = pos(rng);
  for (auto _ : state) {
    for (int i = 0; i < kPoints; i += kRun) {
      tex.EvalInto(kRun, &s[i], &t[i], rgb.data());
      benchmark::DoNotOptimize(rgb.data());
    }
  }
  state.counters["points_per_s"] =
      benchmark::Counter(static_cast<double>(kPoints), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_NoiseTexture)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5);

}  // namespace

// Writing a frame: the 8-bit PNG and the ground-truth OpenEXR of one 2750 x 2200 frame (the dataset writer's
// cost per frame beside the render itself).
const hovs::raytrace::Frame& OneFrame() {
  static const hovs::raytrace::Frame f = [] {
    const hovs::raytrace::RayScene scene(Scene().description);
    hovs::raytrace::RenderOptions ro;
    ro.samples = 1;
    ro.ground_truth = true;
    return hovs::raytrace::Render(scene, hovs::raytrace::ViewCamera::Unit(0), ro);
  }();
  return f;
}

void BM_WriteGroundTruthExr(benchmark::State& state) {
  const auto& f = OneFrame();
  const auto path = std::filesystem::temp_directory_path() / "hovs_bench_truth.exr";
  for (auto _ : state) hovs::raytrace::WriteGroundTruthExr(path, f, {});
  state.counters["MB"] = std::filesystem::file_size(path) / 1e6;
  std::filesystem::remove(path);
}
BENCHMARK(BM_WriteGroundTruthExr)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The channel selections and compressions a dataset can store (hovs dataset --truth, --truth-compression): the
// file's size and write time per frame. Args: selection (0 all twelve, 1 the default Z N id mask, 2 Z and mask),
// compression (0 none, 1 rle, 2 zips, 3 zip, 4 piz).
void BM_WriteGroundTruthChoice(benchmark::State& state) {
  const auto& f = OneFrame();
  const std::vector<std::vector<std::string>> selections = {
      hovs::raytrace::TruthFileOptions::AllGroups(), hovs::raytrace::TruthFileOptions{}.groups, {"Z", "mask"}};
  hovs::raytrace::TruthFileOptions file;
  file.groups = selections[state.range(0)];
  file.compression = hovs::raytrace::TruthFileOptions::Compressions()[state.range(1)];
  const auto path = std::filesystem::temp_directory_path() / "hovs_bench_truth_choice.exr";
  for (auto _ : state) hovs::raytrace::WriteGroundTruthExr(path, f, {}, file);
  state.counters["MB"] = std::filesystem::file_size(path) / 1e6;
  state.SetLabel(file.GroupsText() + " " + file.compression);
  std::filesystem::remove(path);
}
BENCHMARK(BM_WriteGroundTruthChoice)
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2, 3, 4}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

// The dataset writer end to end: 3 full-size frames of the calibration scene at 4 samples per pixel with the
// default ground truth (hovs dataset -n 3 --samples 4), as a user runs it. Counters per frame: the whole frame
// (wall), its render (the manifest's render_seconds) and the rest, the writing (sensor model, PNG, EXR, sidecar,
// thumbnail and page); write_share is writing over the whole (target: at most a third). Arg: 1 default channels,
// 0 all twelve.
void BM_DatasetFrame(benchmark::State& state) {
  auto cfg = hovs::scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
  cfg.render.samples = 4;
  if (state.range(0) == 0) cfg.render.truth_file.groups = hovs::raytrace::TruthFileOptions::AllGroups();
  hovs::scenes::DatasetOptions o;
  o.count = 3;
  const auto out = std::filesystem::temp_directory_path() / "hovs_bench_dataset";
  double wall = 0, render = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    hovs::scenes::WriteCalibrationDataset(cfg, o, out, {{"hovs", "bench"}});
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // (Read as plain JSON: a manifest loaded by the library counts as an input, which the next run's output
    // folder may not replace.)
    std::ifstream manifest(out / "dataset.json");
    const nlohmann::json m = nlohmann::json::parse(manifest);
    for (const auto& fr : m["frames"]) render += fr["render_seconds"].get<double>();
    std::filesystem::remove_all(out);
  }
  const double frames = static_cast<double>(state.iterations() * o.count);
  state.counters["frame_s"] = wall / frames;
  state.counters["render_s"] = render / frames;
  state.counters["write_s"] = (wall - render) / frames;
  state.counters["write_share"] = (wall - render) / wall;
}
BENCHMARK(BM_DatasetFrame)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// The sensor model over one frame (vignetting, shot and read noise, 8-bit range), as the dataset writer applies it
// before the PNG: a fresh 2750 x 2200 x 3 float image per frame.
void BM_ApplySensor(benchmark::State& state) {
  const auto& f = OneFrame();
  hovs::raytrace::SensorOptions s;
  s.vignetting = 0.3, s.full_well = 10000, s.read_noise = 5;
  int channels = 0;
  for (auto _ : state) benchmark::DoNotOptimize(hovs::raytrace::ApplySensor(f, s, 1, &channels).data());
}
BENCHMARK(BM_ApplySensor)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void BM_WritePng(benchmark::State& state) {
  const auto& f = OneFrame();
  const auto path = std::filesystem::temp_directory_path() / "hovs_bench_image.png";
  for (auto _ : state) hovs::io::WriteImage(path, f.width, f.height, 3, f.rgb, 8);
  state.counters["MB"] = std::filesystem::file_size(path) / 1e6;
  std::filesystem::remove(path);
}
BENCHMARK(BM_WritePng)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// Reading a full-size 8-bit RGB PNG as float channels (what `hovs unwrap`, replay and the model files read per
// image).
void BM_ReadPng(benchmark::State& state) {
  const auto& f = OneFrame();
  const auto path = std::filesystem::temp_directory_path() / "hovs_bench_read.png";
  hovs::io::WriteImage(path, f.width, f.height, 3, f.rgb, 8);
  int w = 0, h = 0, c = 0;
  for (auto _ : state) benchmark::DoNotOptimize(hovs::io::ReadImage(path, &w, &h, &c).data());
  std::filesystem::remove(path);
}
BENCHMARK(BM_ReadPng)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

// Reading a full-size ground-truth OpenEXR file into named channels (`hovs depth` reads one per view).
void BM_ReadGroundTruthExr(benchmark::State& state) {
  const auto& f = OneFrame();
  const auto path = std::filesystem::temp_directory_path() / "hovs_bench_read.exr";
  hovs::raytrace::WriteGroundTruthExr(path, f, {});
  for (auto _ : state) benchmark::DoNotOptimize(hovs::io::ReadExr(path).width);
  std::filesystem::remove(path);
}
BENCHMARK(BM_ReadGroundTruthExr)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
