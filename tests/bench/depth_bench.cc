// Dense depth speed: two 2048 x 512 rectified panoramas (target: at most 150 ms on the 2-core machine).
// Arguments: disparities, coarse to fine (0: SGBM at full resolution; 1: SGBM at half resolution + block search).
// Content: smoothed noise and the same shifted by 40 columns (SGBM's cost does not depend on the content).
#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include "depth/stereo.h"
#include "tests/core/test_rigs.h"

namespace {

using namespace hovs;

void BM_DenseDepth(benchmark::State& state) {
  const auto rig0 = test::AlignedRig();
  const depth::StereoRig rig{AnyModel::Exact(rig0), AnyModel::Exact(rig0), Rigid3d::Translation(Vec3d(-0.64, 0, 0))};
  depth::RectifyOptions ro;  // 2048 x 512
  const depth::Rectification r = depth::Rectify(rig, ro);
  cv::Mat a(ro.height, ro.width + 40, CV_8UC1);
  cv::RNG(3).fill(a, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(a, a, cv::Size(5, 5), 1.2);
  unwrap::Image8 left, right;
  left.width = right.width = ro.width, left.height = right.height = ro.height, left.channels = right.channels = 1;
  left.data.resize(size_t(ro.width) * ro.height), right.data.resize(left.data.size());
  for (int v = 0; v < ro.height; ++v)
    for (int u = 0; u < ro.width; ++u) {
      left.data[size_t(v) * ro.width + u] = a.at<uint8_t>(v, u);
      right.data[size_t(v) * ro.width + u] = a.at<uint8_t>(v, u + 40);
    }
  depth::DenseOptions o;
  o.num_disparities = static_cast<int>(state.range(0));
  o.coarse_to_fine = state.range(1) != 0;
  for (auto _ : state) {
    const auto d = depth::ComputeDenseDepth(r, left, right, o);
    benchmark::DoNotOptimize(d.range.data());
  }
}
BENCHMARK(BM_DenseDepth)
    ->Args({320, 0})
    ->Args({192, 0})
    ->Args({64, 0})
    ->Args({320, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
