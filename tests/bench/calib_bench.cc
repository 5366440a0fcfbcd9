// Monocular calibration speed: checkerboard detection on a rendered 2750 x 2200 catadioptric image and on a real
// VMR image (target: at most 0.5 s per 2750 x 2200 image), and the joint polynomial solve for 9 images x 35
// corners (target: at most 50 ms), on the 2-core machine.
#include <benchmark/benchmark.h>

#include <opencv2/imgcodecs.hpp>

#include "calib/checkerboard_detector.h"
#include "calib/polynomial_calibration.h"
#include "core/io.h"
#include "scenes/dataset.h"
#include "tests/calib/synthetic_boards.h"
#include "tests/core/test_rigs.h"

namespace {

using namespace hovs;

// One rendered frame of the reference calibration set (rendered once per process).
const cv::Mat& RenderedFrame() {
  static const cv::Mat img = [] {
    auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
    cfg.render.samples = 4;
    scenes::DatasetOptions o;
    o.count = 1;
    const auto dir = std::filesystem::temp_directory_path() / "hovs-calib-bench";
    scenes::WriteCalibrationDataset(cfg, o, dir, {{"hovs", "bench"}});
    cv::Mat m = cv::imread((dir / "images" / "unit0_0000.png").string(), cv::IMREAD_GRAYSCALE);
    std::filesystem::remove_all(dir);
    return m;
  }();
  return img;
}

void BM_DetectCheckerboardRendered2750x2200(benchmark::State& state) {
  const cv::Mat& img = RenderedFrame();
  calib::CheckerboardDetectOptions o;
  o.board = {7, 5, 0.03};
  for (auto _ : state) {
    const auto d = calib::DetectCheckerboard(img, o);
    if (!d.complete) state.SkipWithError("board not found");
    benchmark::DoNotOptimize(d.pixels.data());
  }
}
BENCHMARK(BM_DetectCheckerboardRendered2750x2200)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

void BM_DetectCheckerboardVmr1024x768(benchmark::State& state) {
  const cv::Mat img =
      cv::imread(std::string(HOVS_SOURCE_DIR) + "/../shared/data/vmr/VMRImage0.jpg", cv::IMREAD_GRAYSCALE);
  calib::CheckerboardDetectOptions o;
  o.board = {7, 6, 0.03};
  for (auto _ : state) {
    const auto d = calib::DetectCheckerboard(img, o);
    if (!d.complete) state.SkipWithError("board not found");
    benchmark::DoNotOptimize(d.pixels.data());
  }
}
BENCHMARK(BM_DetectCheckerboardVmr1024x768)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// 9 boards of 7 x 5 corners around the reference unit, 0.1 px noise, degree 4, with covariance.
void BM_CalibratePolynomial9x35(benchmark::State& state) {
  const auto rig = test::AlignedRig();
  const auto obs = calib::SyntheticObservations(rig, 9, 0.1, 7);
  calib::PolynomialCalibrationOptions po;
  for (auto _ : state) {
    const auto r = calib::CalibratePolynomial(obs, rig.camera.width, rig.camera.height, po);
    benchmark::DoNotOptimize(r.rms);
  }
}
BENCHMARK(BM_CalibratePolynomial9x35)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace
