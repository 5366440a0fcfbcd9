// Design-study speed: the 1000 x 1000 (a, b) sweep (target: at most 1 s on the 2-core CI machine) and the
// constrained optimum.
#include <benchmark/benchmark.h>

#include "design/config.h"
#include "design/design.h"
#include "optics/focus.h"

namespace {

hovs::design::DesignConfig Reference() {
  return hovs::design::LoadDesignConfig(std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml");
}

void BM_Sweep(benchmark::State& state) {
  const auto cfg = Reference();
  const hovs::design::SweepSpec spec{static_cast<int>(state.range(0)), static_cast<int>(state.range(0)), 1};
  for (auto _ : state) {
    auto r = hovs::design::Sweep(cfg.problem, spec);
    benchmark::DoNotOptimize(r.objective.data());
  }
  state.counters["designs_per_s"] =
      benchmark::Counter(static_cast<double>(spec.na) * spec.nb, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Sweep)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OptimizeContinuous(benchmark::State& state) {
  const auto cfg = Reference();
  const auto sweep = hovs::design::Sweep(cfg.problem, cfg.sweep);
  for (auto _ : state) benchmark::DoNotOptimize(hovs::design::OptimizeContinuous(cfg.problem, sweep).objective);
}
BENCHMARK(BM_OptimizeContinuous)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IntegerMillimetre(benchmark::State& state) {
  const auto cfg = Reference();
  for (auto _ : state) benchmark::DoNotOptimize(hovs::design::OptimizeIntegerMillimetre(cfg.problem));
}
BENCHMARK(BM_IntegerMillimetre)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

// The blur atlas of a design report: 64 elevations x 32 scene distances x 256 pupil rays of the reference design at
// f/4, traced (law of reflection per pupil point) and reduced to spots and MTF figures. Target: <= 1 s on 2 cores.
void BM_BlurAtlas(benchmark::State& state) {
  const hovs::design::DesignConfig cfg =
      hovs::design::LoadDesignConfig(std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml");
  const hovs::design::DesignPoint p{0.048, 0.044, 0.080};
  const hovs::design::Metrics m = hovs::design::Evaluate(p, cfg.problem);
  hovs::optics::OpticalSystem sys;
  sys.rig = hovs::design::RigOf(p, cfg.problem.camera);
  sys.lens = cfg.problem.camera.Lens();
  sys.lens.f_number = 4;
  sys.pixel_pitch = cfg.problem.camera.pixel_pitch;
  const auto fields = hovs::optics::FieldGrid(m.lower_deg, m.upper_deg, 64, hovs::optics::DistanceGrid(1.0, 1e4, 32));
  for (auto _ : state) {
    const auto atlas = hovs::optics::Atlas(sys, fields, 0.1537);
    benchmark::DoNotOptimize(atlas.data());
  }
  state.counters["pupil_rays"] = benchmark::Counter(double(fields.size()) * sys.pupil_samples);
}
BENCHMARK(BM_BlurAtlas)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
