#include "depth/live_depth.h"

#include <chrono>
#include <cmath>

#include "core/error.h"
#include "depth/evaluation.h"

namespace hovs::depth {
namespace {
using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }
}  // namespace

void LiveDepthOptions::Check(const std::string& where) const {
  rectify.Check(where);
  dense.Check(where);
  HOVS_REQUIRE(dense.num_disparities < rectify.width, where, "the disparity range (", dense.num_disparities,
               ") must be smaller than the rectified width (", rectify.width, ")");
  HOVS_REQUIRE(max_points >= 1, where, "the cloud needs at least one point");
}

LiveDepth::LiveDepth(const StereoRig& rig, const LiveDepthOptions& options,
                     std::function<void(const LiveDepthResult&)> on_result)
    : options_(options), on_result_(std::move(on_result)) {
  options_.Check("live depth");
  rect_ = Rectify(rig, options_.rectify);
  thread_ = std::thread([this] { Run(); });
}

LiveDepth::~LiveDepth() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool LiveDepth::Offer(std::vector<uint8_t>* left, std::vector<uint8_t>* right, int width, int height,
                      unwrap::PixelFormat format, uint64_t stamp_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.offered;
  if (busy_) {
    ++stats_.skipped;
    return false;
  }
  left_.swap(*left), right_.swap(*right);
  width_ = width, height_ = height, format_ = format, stamp_ns_ = stamp_ns;
  busy_ = true;
  cv_.notify_all();
  return true;
}

bool LiveDepth::Drain(double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  return cv_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return !busy_; });
}

LiveDepthStats LiveDepth::Stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void LiveDepth::Run() {
  unwrap::Remapper ml(rect_.left), mr(rect_.right);
  std::vector<unwrap::Image8> left, right;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return busy_ || stop_; });
      if (!busy_) return;
    }
    // The buffers are this thread's until busy_ is cleared: Offer does not touch them meanwhile.
    const auto t0 = Clock::now();
    const size_t bpp = format_ == unwrap::PixelFormat::kRgb8 ? 3 : 1;
    ml.Run({left_.data(), width_, height_, size_t(width_) * bpp, format_}, unwrap::Interpolation::kBilinear, &left);
    mr.Run({right_.data(), width_, height_, size_t(width_) * bpp, format_}, unwrap::Interpolation::kBilinear, &right);
    const auto t1 = Clock::now();
    const DenseDepth d = ComputeDenseDepth(rect_, left[0], right[0], options_.dense);
    const auto t2 = Clock::now();
    LiveDepthResult r;
    r.stamp_ns = stamp_ns_;
    r.depth = &d;
    std::vector<ColouredPoint> pts;
    std::vector<float> sig;
    SubsampledCloud(rect_, d, left[0], options_.max_points, &pts, &sig);
    r.xyz.reserve(3 * pts.size()), r.rgb.reserve(3 * pts.size());
    for (const auto& p : pts)
      for (int a = 0; a < 3; ++a) r.xyz.push_back(static_cast<float>(p.p[a])), r.rgb.push_back(p.rgb[a]);
    r.range = d.range;
    const auto t3 = Clock::now();
    if (on_result_) on_result_(r);
    const auto t4 = Clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.rectify_ms.push_back(Ms(t0, t1)), stats_.match_ms.push_back(Ms(t1, t2));
    stats_.cloud_ms.push_back(Ms(t2, t3)), stats_.total_ms.push_back(Ms(t0, t4));
    ++stats_.computed;
    busy_ = false;
    cv_.notify_all();
  }
}

}  // namespace hovs::depth
