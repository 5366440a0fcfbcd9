// hovs live --publish end to end on a private loopback: a replayed camera expanded into three views, every frame
// received by a subscriber in this process, identical to the views hovs writes, with ROS 2's layout and the
// frames' arrival stamps; and the DDS options' errors.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <future>
#include <map>
#include <thread>
#include <nlohmann/json.hpp>

#include "core/io.h"
#include "io/image_io.h"
#include "stream/subscriber.h"
#include "tests/cli_helper.h"
#include "tests/stream/cdr_reader.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

constexpr char kModel[] = R"(%YAML:1.0
---
image_width: 320
image_height: 240
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 80., 0., 159.5, 0., 80., 119.5, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 4
   dt: d
   data: [ 0., 0., 0., 0. ]
xi: 1.0
)";

constexpr char kLayout[] = R"(views:
  - {name: front, type: perspective, width: 64, height: 48, yaw: 0, pitch: -30, roll: 0, hfov: 60}
  - {name: back-left, type: perspective, width: 64, height: 48, yaw: 150, pitch: -30, roll: 0, hfov: 60}
  - {name: pano, type: cylindrical, width: 200, height: 40, elevation_min: -60, elevation_max: -10}
)";

uint64_t NowNs() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
}

TEST(LivePublishCli, EveryReplayedFrameReachesASubscriberAsHovsWritesIt) {
  const fs::path dir = test::Scratch("live-publish", "work");
  fs::create_directories(dir / "frames");
  for (int k = 0; k < 4; ++k) {
    std::vector<float> px(320 * 240);
    for (size_t i = 0; i < px.size(); ++i)
      px[i] = static_cast<float>((((i % 320) * (k + 1) + (i / 320) * 3 + 17 * k) % 256) / 255.0);
    io::WriteImage(dir / "frames" / ("f" + std::to_string(k) + ".png"), 320, 240, 1, px, 8);
  }
  WriteFileAtomic(dir / "cam.yaml", kModel);
  WriteFileAtomic(dir / "layout.yaml", kLayout);

  stream::DdsOptions o;
  o.domain = 51, o.interface = "lo", o.peers = {"127.0.0.1"};
  const std::vector<std::pair<std::string, stream::MessageType>> topics = {
      {"/robot/front/image_raw", stream::MessageType::kImage},
      {"/robot/front/camera_info", stream::MessageType::kCameraInfo},
      {"/robot/back_left/image_raw", stream::MessageType::kImage},
      {"/robot/back_left/camera_info", stream::MessageType::kCameraInfo},
      {"/robot/pano/image_raw", stream::MessageType::kImage}};
  std::map<std::string, std::unique_ptr<stream::Subscriber>> subs;
  for (const auto& [t, type] : topics) subs[t] = std::make_unique<stream::Subscriber>(o, t, type, 256);

  const uint64_t t_start = NowNs();
  auto run = std::async(std::launch::async, [&] {
    return test::Hovs("-q live --replay " + (dir / "frames").string() + " --loop --model " +
                      (dir / "cam.yaml").string() + " --layout " + (dir / "layout.yaml").string() +
                      " --frames 100 --write-every 1 --publish --domain 51 --dds-interface lo --dds-peer 127.0.0.1 "
                      "--topic-prefix robot --wait-subscribers 30 --out " +
                      (dir / "live").string());
  });
  std::map<std::string, std::vector<std::vector<uint8_t>>> got;
  int idle = 0;
  for (bool all = false; !all && idle < 600;) {
    bool any = false;
    all = true;
    for (auto& [t, s] : subs) {
      while (auto m = s->Take(0.0)) got[t].push_back(std::move(*m)), any = true;
      all = all && got[t].size() >= 100;
    }
    idle = any ? 0 : idle + 1;
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const auto r = run.get();
  const uint64_t t_end = NowNs();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& [t, type] : topics) ASSERT_EQ(got[t].size(), 100u) << t;

  const auto j = nlohmann::json::parse(ReadFile(dir / "live/live.json"));
  EXPECT_EQ(j["dds"]["frames"]["published"], 100);
  EXPECT_EQ(j["dds"]["frames"]["dropped"], 0);
  EXPECT_EQ(j["dds"]["topics"].size(), 5u);
  EXPECT_TRUE(j["latency"]["publish"].contains("median_ms"));

  uint64_t last = 0;
  for (int k = 0; k < 100; ++k) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "frame%06d", k);
    uint64_t stamp = 0;
    for (const char* view : {"front", "back-left", "pano"}) {
      const std::string ros = std::string(view) == "back-left" ? "back_left" : view;
      const test::RosImage m = test::DecodeImage(got["/robot/" + ros + "/image_raw"][k]);
      int w = 0, h = 0, c = 0;
      const auto px = io::ReadImage(dir / "live" / (std::string(stem) + "_" + view + ".png"), &w, &h, &c);
      ASSERT_EQ(m.width, uint32_t(w)) << view;
      ASSERT_EQ(m.height, uint32_t(h)) << view;
      EXPECT_EQ(m.encoding, "mono8");
      EXPECT_EQ(m.step, uint32_t(w));
      EXPECT_EQ(m.header.frame_id, "robot_" + ros);
      ASSERT_EQ(m.data.size(), px.size());
      size_t differ = 0;
      for (size_t i = 0; i < px.size(); ++i) differ += m.data[i] != std::lround(px[i] * 255);
      EXPECT_EQ(differ, 0u) << stem << " " << view;
      const uint64_t s = uint64_t(m.header.sec) * 1'000'000'000ull + m.header.nanosec;
      if (stamp == 0) stamp = s;
      EXPECT_EQ(s, stamp) << "every view of a frame carries the frame's stamp";
    }
    EXPECT_GT(stamp, last) << "frame " << k;
    EXPECT_GE(stamp, t_start);
    EXPECT_LE(stamp, t_end);
    last = stamp;
    const test::RosCameraInfo info = test::DecodeCameraInfo(got["/robot/front/camera_info"][k]);
    EXPECT_EQ(uint64_t(info.header.sec) * 1'000'000'000ull + info.header.nanosec, stamp);
    EXPECT_EQ(info.width, 64u);
    EXPECT_NEAR(info.k[0], 32 / std::tan(M_PI / 6), 1e-9);
  }
}

TEST(LivePublishCli, DdsOptionsThatCannotWorkAreRefusedByName) {
  const fs::path dir = test::Scratch("live-publish", "bad");
  fs::create_directories(dir);
  io::WriteImage(dir / "f.png", 320, 240, 1, std::vector<float>(320 * 240, 0.5f), 8);
  WriteFileAtomic(dir / "cam.yaml", kModel);
  WriteFileAtomic(dir / "layout.yaml", kLayout);
  const std::string base = "live --replay " + dir.string() + " --model " + (dir / "cam.yaml").string() + " --layout " +
                           (dir / "layout.yaml").string() + " --frames 1 ";
  const auto domain = test::Hovs(base + "--publish --domain 233");
  EXPECT_EQ(domain.exit_code, 2) << domain.output;
  EXPECT_NE(domain.output.find("--domain"), std::string::npos) << domain.output;
  const auto iface = test::Hovs(base + "--publish --dds-interface hovs-none0");
  EXPECT_EQ(iface.exit_code, 2) << iface.output;
  EXPECT_NE(iface.output.find("hovs-none0"), std::string::npos) << iface.output;
  const auto nopub = test::Hovs(base + "--domain 3");
  EXPECT_EQ(nopub.exit_code, 2) << nopub.output;
  EXPECT_NE(nopub.output.find("--publish"), std::string::npos) << nopub.output;
  const auto env = test::Run("ROS_DOMAIN_ID=abc " + std::string(HOVS_BINARY) + " " + base + "--publish");
  EXPECT_EQ(env.exit_code, 2) << env.output;
  EXPECT_NE(env.output.find("ROS_DOMAIN_ID"), std::string::npos) << env.output;
}

}  // namespace
}  // namespace hovs
