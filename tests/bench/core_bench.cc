// Per-point cost of the core projections (single-viewpoint closed form, law-of-reflection solve,
// back-projection, polynomial world2cam).
#include <benchmark/benchmark.h>

#include "core/model_fit.h"
#include "tests/core/test_rigs.h"

namespace {

using hovs::Vec2d;
using hovs::Vec3d;

void BM_ProjectClosedForm(benchmark::State& state) {
  const auto rig = hovs::test::AlignedRig();
  const auto pts = hovs::test::WorldPoints(4096, 1);
  size_t i = 0;
  for (auto _ : state) {
    Vec2d uv;
    benchmark::DoNotOptimize(rig.ImgFromMirrorSvp(pts[i++ & 4095], &uv));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ProjectClosedForm);

void BM_ProjectLawOfReflection(benchmark::State& state) {
  const auto rig = hovs::test::MisalignedRig();
  const auto pts = hovs::test::WorldPoints(4096, 1);
  size_t i = 0;
  for (auto _ : state) {
    Vec2d uv;
    benchmark::DoNotOptimize(rig.ImgFromMirrorGeneral(pts[i++ & 4095], &uv));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ProjectLawOfReflection);

void BM_BackProject(benchmark::State& state) {
  const auto rig = hovs::test::AlignedRig();
  const auto px = hovs::test::MirrorPixels(rig, 40);
  size_t i = 0;
  for (auto _ : state) {
    Vec3d M, d;
    benchmark::DoNotOptimize(rig.RayFromImg(px[i++ % px.size()], &M, &d));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_BackProject);

void BM_PolynomialWorldToCamExact(benchmark::State& state) {
  const auto poly = hovs::PolynomialFromCatadioptric(hovs::test::AlignedRig(), 4);
  const auto pts = hovs::test::WorldPoints(4096, 1);
  size_t i = 0;
  for (auto _ : state) {
    Vec2d uv;
    benchmark::DoNotOptimize(poly.ImgFromCam(pts[i++ & 4095], &uv));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PolynomialWorldToCamExact);

}  // namespace
