// Publishing a pipeline's output over DDS without ever holding the pipeline up: the pipeline hands each frame's
// bundle (views, point cloud) to a writer thread by swapping buffers, and a bundle the thread has not taken yet
// when the next one arrives is replaced by it and counted as dropped. A reader that is slow or gone (whose
// acknowledgements a reliable writer waits for, at most DdsOptions::max_blocking_s) costs frames on the wire,
// counted, never time in the pipeline.
//
// Topics (ROS 2 names; DDS names with the rt/ prefix), for a prefix P and each image topic's name N:
//   /P/N/image_raw     sensor_msgs/Image, rgb8 or mono8 (or 32FC1 for a range image)
//   /P/N/camera_info   sensor_msgs/CameraInfo, for pinhole (perspective) views: K, R = I, P = [K | 0], no
//                      distortion, sent with every image and the same stamp
//   /P/points          sensor_msgs/PointCloud2: x, y, z float32 in metres (+ rgb packed in a float32, as PCL)
// Every message of a bundle carries its stamp (the frame's arrival, Unix time) and frame_id P_N (P_points).
#pragma once

#include <array>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "stream/dds.h"
#include "unwrap/layout.h"
#include "unwrap/remap.h"

namespace hovs::stream {

struct CameraInfo {
  int width = 0, height = 0;
  std::string distortion_model = "plumb_bob";
  std::vector<double> d = std::vector<double>(5, 0.0);
  std::array<double, 9> k{}, r{};
  std::array<double, 12> p{};
};
// The pinhole model of a perspective view (nullopt for panoramas, which no CameraInfo describes).
std::optional<CameraInfo> CameraInfoOfView(const unwrap::ViewSpec& spec);

struct PointCloud {
  int width = 0, height = 1;  // organised clouds: height rows; unorganised: height 1
  std::vector<float> xyz;     // 3 per point, metres; NaN for a pixel without a point (then not dense)
  std::vector<uint8_t> rgb;   // 3 per point, or empty
};

struct Bundle {
  uint64_t stamp_ns = 0;               // nanoseconds since the Unix epoch
  std::vector<unwrap::Image8> images;  // one per image topic, in PublisherTopics::images' order
  PointCloud cloud;                    // sent when the publisher has a cloud topic and cloud.width > 0
};

struct PublisherTopics {
  std::string prefix = "hovs";
  struct Image {
    std::string name;
    std::optional<CameraInfo> info;
    // Empty: mono8 or rgb8 by the image's channels. "32FC1": a float image (a range image in metres, NaN where
    // unknown), whose Image8 carries 4 bytes per pixel (channels = 4).
    std::string encoding;
  };
  std::vector<Image> images;
  bool cloud = false;
};

// The topics of a layout's views: an image topic per view, with its CameraInfo when it is perspective.
PublisherTopics TopicsOfViews(const std::vector<unwrap::ViewSpec>& views, const std::string& prefix, bool cloud);

struct PublishStats {
  uint64_t offered = 0;         // bundles handed over
  uint64_t published = 0;       // bundles whose every message was written
  uint64_t dropped = 0;         // replaced before the writer thread took them
  uint64_t incomplete = 0;      // taken, but some message was not written (offered = published + dropped + these)
  uint64_t write_timeouts = 0;  // messages a reliable reader's acknowledgements held past max_blocking_s
  uint64_t write_errors = 0;    // other refused writes
  double write_ms_total = 0, write_ms_max = 0;  // the writer thread's time per bundle
  nlohmann::json ToJson() const;
};

class Publisher {
 public:
  // Creates the participant and a writer per topic; throws hovs::Error naming what Cyclone refuses.
  Publisher(const DdsOptions& options, const PublisherTopics& topics);
  ~Publisher();  // writes what was offered (at most 2 s more), then stops
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  // Swaps *bundle with the publisher's spare: *bundle comes back holding an older bundle's buffers (reusable,
  // sizes kept). Returns at once; a bundle still waiting for the writer thread is replaced and counted dropped.
  // With `wait` (replays, recordings: no deadline), waits for the thread to take the waiting bundle instead.
  // Throws when the images do not match the topics (count, sizes of a CameraInfo).
  void Offer(Bundle* bundle, bool wait = false);
  // True when every image (and cloud) topic has at least `count` matched readers (waits up to timeout_s); with
  // camera_info, every CameraInfo topic as well (a reader that must see every CameraInfo, as a test).
  bool WaitForSubscribers(int count, double timeout_s, bool camera_info = false);
  // True when every offered bundle has been written (or dropped) and every matched reader has acknowledged
  // every written sample, within timeout_s.
  bool Flush(double timeout_s);
  PublishStats Stats() const;
  // Each topic as "ROS name (type)", in creation order.
  std::vector<std::string> Topics() const;

 private:
  struct Writers;
  void Run();
  void Write(const Bundle& b);

  PublisherTopics topics_;
  std::unique_ptr<Participant> participant_;
  std::unique_ptr<Writers> writers_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  Bundle slot_, working_;
  bool pending_ = false, writing_ = false, stop_ = false;
  PublishStats stats_;
  std::thread thread_;
};

}  // namespace hovs::stream
