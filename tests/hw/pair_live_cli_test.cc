// hovs live over two units: frame pairs from two GigE Vision simulators (127.0.0.1 and 127.0.0.2 inside a private
// network namespace) expanded into the binocular preset's 3 + 3 views and published on DDS; pairs counted, views
// received; and the errors of pairs and rigs that do not fit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/io.h"
#include "io/image_io.h"
#include "stream/subscriber.h"
#include "tests/cli_helper.h"
#include "tests/stream/cdr_reader.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;
using test::Hovs;

std::string Src(const std::string& rel) { return std::string(HOVS_SOURCE_DIR) + "/" + rel; }

TEST(PairLiveCli, TwoSimulatedUnitsExpandTogetherAndReachASubscriber) {
  const fs::path dir = test::Scratch("pair-live", "run");
  const auto set = Hovs("--quiet dataset --kind stereo_aruco --scene " + Src("scenes/reference_stereo.yaml") +
                        " --count 3 --samples 1 --seed 3 --downscale 5 --truth none -o " + (dir / "set").string());
  ASSERT_EQ(set.exit_code, 0) << set.output;
  const std::string manifest = (dir / "set/dataset.json").string();

  stream::DdsOptions o;
  o.domain = 61, o.interface = "lo", o.peers = {"127.0.0.1"};
  std::map<std::string, std::unique_ptr<stream::Subscriber>> subs;
  for (const char* v :
       {"unit0_view120", "unit0_view180", "unit0_view240", "unit1_view300", "unit1_view0", "unit1_view60"})
    subs[v] = std::make_unique<stream::Subscriber>(o, std::string("/hovs/") + v + "/image_raw",
                                                   stream::MessageType::kImage, 256);
  stream::Subscriber points(o, "/hovs/points", stream::MessageType::kPointCloud2, 64);
  stream::Subscriber range(o, "/hovs/depth/image_raw", stream::MessageType::kImage, 64);
  auto run = std::async(std::launch::async, [&] {
    return Hovs("-q live --simulate " + manifest + " --model " + manifest +
                " --layout binocular --frames 30 --frame-rate 10 --pair-tolerance-ms 50 --write-every 10 --publish "
                "--domain 61 --dds-interface lo --dds-peer 127.0.0.1 --wait-subscribers 20 --depth --depth-size "
                "512x128 --depth-disparities 64 -o " +
                (dir / "live").string());
  });
  std::map<std::string, std::vector<std::vector<uint8_t>>> got;
  for (int idle = 0; idle < 200;) {
    bool any = false;
    for (auto& [t, s] : subs)
      while (auto m = s->Take(0.0)) got[t].push_back(std::move(*m)), any = true;
    bool all = true;
    for (auto& [t, s] : subs) all = all && got[t].size() >= 30;
    if (all) break;
    idle = any ? 0 : idle + 1;
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const auto r = run.get();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(ReadFile(dir / "live/live.json"));
  EXPECT_EQ(j["frames_processed"], 30);
  EXPECT_EQ(j["views"], 6);
  EXPECT_EQ(j["pairs"]["units"], nlohmann::json({"left", "right"}));
  EXPECT_LE(j["pairs"]["skew"]["max_ms"].get<double>(), 50.0);  // the tolerance asked for
  EXPECT_EQ(j["source"].size(), 2u);
  EXPECT_EQ(j["dds"]["frames"]["published"].get<int>() + j["dds"]["frames"]["dropped"].get<int>() +
                j["dds"]["frames"]["incomplete"].get<int>(),
            30);
  // Every published frame arrived (the loopback loses nothing; a frame the writer had not taken is counted).
  const int published = j["dds"]["frames"]["published"];
  EXPECT_GE(published, 25);
  for (const auto& [t, msgs] : got) {
    EXPECT_EQ(static_cast<int>(msgs.size()), published) << t;
    const test::RosImage m = test::DecodeImage(msgs.front());
    EXPECT_EQ(m.width, 1200u);
    EXPECT_EQ(m.height, 700u);
    EXPECT_EQ(m.encoding, "mono8");
  }
  for (const char* f : {"frame000000_unit0_view120.png", "frame000020_unit1_view60.png"})
    EXPECT_TRUE(fs::exists(dir / "live" / f)) << f;

  // Depth ran beside the expansion: its results were published and the last cloud written.
  const auto& d = j["depth"];
  ASSERT_TRUE(d.is_object()) << j.dump(1);
  EXPECT_GE(d["depth_computed"].get<int>(), 1);
  EXPECT_EQ(d["depth_computed"].get<int>() + d["pairs_skipped"].get<int>(), 30);
  EXPECT_NEAR(d["baseline_m"].get<double>(), 0.641, 0.002);
  EXPECT_TRUE(fs::exists(dir / "live/points.ply"));
  const int depth_published = d["dds"]["frames"]["published"];
  EXPECT_GE(depth_published, 1);
  std::vector<std::vector<uint8_t>> clouds, ranges;
  for (int k = 0; k < 100 && int(clouds.size()) < depth_published; ++k)
    if (auto m = points.Take(0.1)) clouds.push_back(*m);
  while (auto m = range.Take(0.5)) ranges.push_back(*m);
  EXPECT_EQ(int(clouds.size()), depth_published);
  EXPECT_EQ(int(ranges.size()), depth_published);
  ASSERT_FALSE(clouds.empty());
  const test::RosPointCloud2 pc = test::DecodePointCloud2(clouds.back());
  EXPECT_EQ(pc.header.frame_id, "hovs_points");
  ASSERT_EQ(pc.fields.size(), 4u);
  EXPECT_EQ(pc.point_step, 16u);
  ASSERT_GT(pc.width, 1000u);
  // The scene is a textured floor 1.3 m below the units plus the standing boards: the median height is the
  // floor's, and most points lie below the units at plausible ranges. Which of the three stereo pairs the last
  // cloud comes from depends on the machine's load; over the three, the median height is -1.280 to -1.290 m and
  // 89.9 to 91.1 % of the points are below and in range (the rest are on the boards and at the far floor).
  int below = 0;
  std::vector<float> heights;
  for (uint32_t i = 0; i < pc.width; ++i) {
    float xyz[3];
    std::memcpy(xyz, &pc.data[16 * i], 12);
    const double dist = std::sqrt(xyz[0] * xyz[0] + xyz[1] * xyz[1] + xyz[2] * xyz[2]);
    below += xyz[2] < -0.5 && dist > 1.0 && dist < 40.0;
    heights.push_back(xyz[2]);
  }
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  EXPECT_NEAR(heights[heights.size() / 2], -1.3, 0.05);
  EXPECT_GT(below, static_cast<int>(0.85 * pc.width)) << below << " of " << pc.width;
  ASSERT_FALSE(ranges.empty());
  const test::RosImage ri = test::DecodeImage(ranges.back());
  EXPECT_EQ(ri.encoding, "32FC1");
  EXPECT_EQ(ri.width, 512u);
  EXPECT_EQ(ri.height, 128u);
  EXPECT_EQ(ri.step, 512u * 4);
  EXPECT_EQ(ri.data.size(), 512u * 128 * 4);
}

TEST(PairLiveCli, PairsAndRigsThatDoNotFitAreRefusedByName) {
  const fs::path dir = test::Scratch("pair-live", "bad");
  const auto set = Hovs("--quiet dataset --kind stereo_aruco --scene " + Src("scenes/reference_stereo.yaml") +
                        " --count 1 --samples 1 --seed 3 --downscale 5 --truth none -o " + (dir / "set").string());
  ASSERT_EQ(set.exit_code, 0) << set.output;
  const std::string manifest = (dir / "set/dataset.json").string();
  const auto expect_error = [&](const std::string& args, const std::string& needle) {
    const auto r = Hovs("live " + args + " --frames 1 -o " + (dir / "out").string());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << args;
  };
  // One source for a two-unit layout.
  expect_error("--replay " + manifest + " --model " + manifest + " --layout binocular", "one source");
  // A rig model without a second unit.
  expect_error("--replay " + manifest + " --units left --units right --model " + Src("scenes/reference_board.yaml") +
                   " --layout binocular",
               "several units");
  // Sources named after units the rig does not have.
  expect_error("--replay " + manifest + " --units left --units middle --model " + manifest + " --layout binocular",
               "middle");
  // Depth without pairs, and a depth size that is not WxH.
  expect_error("--replay " + manifest + " --model " + manifest + " --layout article --depth", "frame pairs");
  expect_error("--replay " + manifest + " --units left --units right --model " + manifest +
                   " --layout binocular --depth --depth-size 100",
               "--depth-size");
  // A pair whose right frame is smaller than its unit's mapping.
  auto m = nlohmann::json::parse(ReadFile(manifest));
  int w = 0, h = 0, c = 0;
  const auto px = io::ReadImage(dir / "set" / m["frames"][0]["views"][1]["image"].get<std::string>(), &w, &h, &c);
  io::WriteImage(dir / "set/small.png", w / 2, h / 2, c,
                 std::vector<float>(px.begin(), px.begin() + size_t(w / 2) * (h / 2) * c), 8);
  m["frames"][0]["views"][1]["image"] = "small.png";
  WriteFileAtomic(dir / "set/small.json", m.dump(1));
  expect_error("--replay " + (dir / "set/small.json").string() + " --units left --units right --model " + manifest +
                   " --layout binocular",
               "unit right");
}

}  // namespace
}  // namespace hovs
