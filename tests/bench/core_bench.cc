// Per-point cost of the core projections (single-viewpoint closed form, law-of-reflection solve,
// back-projection, polynomial world2cam) and of the renderer's batched mirror reflection.
#include <memory>
#include <benchmark/benchmark.h>

#include "core/hyperboloid.h"
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

// The same points through ImgFromCamBatch, 4096 at a time (as hovs.Camera.project and mapping tables call it).
void BM_PolynomialWorldToCamBatch(benchmark::State& state) {
  const auto poly = hovs::PolynomialFromCatadioptric(hovs::test::AlignedRig(), 4);
  std::vector<double> X;
  for (const Vec3d& p : hovs::test::WorldPoints(4096, 1)) X.insert(X.end(), {p(0), p(1), p(2)});
  std::vector<double> uv(2 * 4096);
  std::unique_ptr<bool[]> ok(new bool[4096]);
  for (auto _ : state) {
    poly.ImgFromCamBatch(X.data(), 4096, uv.data(), ok.get());
    benchmark::DoNotOptimize(uv.data());
  }
  state.SetItemsProcessed(state.iterations() * 4096);
}
BENCHMARK(BM_PolynomialWorldToCamBatch);

// MirrorReflector::ReflectBatch on 256 unit camera rays of the reference rig, as the renderer calls it per chunk of
// samples: a 16 x 16 pixel patch at the image centre's side within the mirror's image disc (argument 0: every ray
// solved) or in the image corner outside the rim (argument 1: blocks answered by the rim-plane test).
void BM_ReflectBatch256(benchmark::State& state) {
  const auto rig = hovs::test::AlignedRig();
  const hovs::MirrorReflector reflector(rig.mirror);
  const Vec3d o = rig.CameraCentre();
  constexpr int n = 256;
  std::vector<double> vx(n), vy(n), vz(n), Mx(n), My(n), Mz(n), dx(n), dy(n), dz(n);
  std::vector<unsigned char> ok(n);
  const Vec2d corner = state.range(0) == 0 ? Vec2d(rig.camera.cx + 600, rig.camera.cy + 300) : Vec2d(40, 40);
  for (int i = 0; i < n; ++i) {
    Vec3d ray;
    rig.camera.CamFromImg(corner + Vec2d(i % 16, i / 16), &ray);
    const Vec3d v = rig.cam_from_mirror.Inverse().Rotate(ray.normalized());
    vx[i] = v.x(), vy[i] = v.y(), vz[i] = v.z();
  }
  for (auto _ : state) {
    reflector.ReflectBatch(o, n, vx.data(), vy.data(), vz.data(), Mx.data(), My.data(), Mz.data(), dx.data(), dy.data(),
                           dz.data(), ok.data());
    benchmark::DoNotOptimize(dx.data());
  }
  int hits = 0;
  for (int i = 0; i < n; ++i) hits += ok[i];
  state.counters["mirror_hits"] = hits;
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_ReflectBatch256)->Arg(0)->Arg(1);

}  // namespace
