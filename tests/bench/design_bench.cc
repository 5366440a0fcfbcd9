// Design-study speed: the 1000 x 1000 (a, b) sweep (target: at most 1 s on the 2-core CI machine) and the
// constrained optimum.
#include <benchmark/benchmark.h>

#include "design/config.h"
#include "design/design.h"

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
