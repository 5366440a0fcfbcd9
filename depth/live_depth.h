// Dense depth beside a live pipeline: a frame pair is handed to the depth thread only when it is idle (its
// buffers swapped in: no copy, nothing queued), rectified, matched coarse to fine, and turned into a range image
// and a point cloud, which a callback receives on the depth thread. The expansion keeps the camera's rate; depth
// runs at the rate the matcher sustains, and the pairs it had no time for are counted as skipped.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "depth/stereo.h"

namespace hovs::depth {

struct LiveDepthOptions {
  RectifyOptions rectify;
  DenseOptions dense;
  int max_points = 100000;  // points of the cloud (evenly spaced valid pixels)
  void Check(const std::string& where) const;
};

struct LiveDepthResult {
  uint64_t stamp_ns = 0;  // the pair's arrival (Unix time)
  const DenseDepth* depth = nullptr;
  std::vector<float> xyz;    // the cloud, left mirror frame, m
  std::vector<uint8_t> rgb;  // its colours (grey repeated for grey frames)
  std::vector<float> range;  // the range image (rectified grid), NaN where masked
};

struct LiveDepthStats {
  uint64_t offered = 0, computed = 0, skipped = 0;
  std::vector<double> rectify_ms, match_ms, cloud_ms, total_ms;
};

class LiveDepth {
 public:
  // Builds the rectification (throws hovs::Error naming the options); starts the thread.
  LiveDepth(const StereoRig& rig, const LiveDepthOptions& options,
            std::function<void(const LiveDepthResult&)> on_result);
  ~LiveDepth();  // finishes the pair in progress, stops
  LiveDepth(const LiveDepth&) = delete;
  LiveDepth& operator=(const LiveDepth&) = delete;

  // When the thread is idle: swaps *left and *right (frames of `width` x `height` in `format`, rows packed) with
  // its spare buffers and returns true; else returns false at once and counts the pair skipped.
  bool Offer(std::vector<uint8_t>* left, std::vector<uint8_t>* right, int width, int height, unwrap::PixelFormat format,
             uint64_t stamp_ns);
  bool Drain(double timeout_s);  // waits for the pair in progress
  LiveDepthStats Stats() const;
  const Rectification& rectification() const { return rect_; }

 private:
  void Run();
  Rectification rect_;
  LiveDepthOptions options_;
  std::function<void(const LiveDepthResult&)> on_result_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<uint8_t> left_, right_;
  int width_ = 0, height_ = 0;
  unwrap::PixelFormat format_ = unwrap::PixelFormat::kGray8;
  uint64_t stamp_ns_ = 0;
  bool busy_ = false, stop_ = false;
  LiveDepthStats stats_;
  std::thread thread_;
};

}  // namespace hovs::depth
