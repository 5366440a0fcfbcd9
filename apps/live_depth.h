// hovs live --depth: dense depth of each frame pair on a thread of its own (depth/live_depth.h) while the views
// keep the camera's rate; its rate and stage latencies in live.json, its range image and point cloud on DDS with
// --publish (/PREFIX/depth/image_raw as 32FC1, /PREFIX/points), the last cloud written as points.ply.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "depth/live_depth.h"
#include "hw/live.h"
#include "stream/publisher.h"

namespace hovs::apps {

struct LiveDepthCliOptions {
  bool depth = false;
  std::string size = "2048x512";  // rectified width x height
  int disparities = 320;
  std::string stereo;  // hovs stereo-calibrate's stereo.json (default: the model's unit poses)
  std::optional<depth::LiveDepthOptions> Resolve() const;  // nullopt without --depth; throws naming the option
};

void AddLiveDepthOptions(CLI::App* sub, LiveDepthCliOptions* o);

class LiveDepthOutput {
 public:
  // rig: the two units (left = the mapping's first unit); dds: publish the results too.
  LiveDepthOutput(const depth::StereoRig& rig, const depth::LiveDepthOptions& options,
                  const std::optional<stream::DdsOptions>& dds, const std::string& prefix);
  // For RunPairLive: offers the pair's frames (their buffers) to the depth thread when it is idle.
  hw::PairFramesSink Sink();
  // Waits for the pair in progress, then the figures for live.json; writes the last cloud to out_dir/points.ply.
  nlohmann::json Finish(const std::filesystem::path& out_dir, double run_seconds);

 private:
  std::unique_ptr<stream::Publisher> publisher_;
  std::unique_ptr<depth::LiveDepth> worker_;
  std::mutex mutex_;
  std::vector<float> last_xyz_;
  std::vector<uint8_t> last_rgb_;
  stream::Bundle bundle_;
  int rect_width_ = 0, rect_height_ = 0;
};

}  // namespace hovs::apps
