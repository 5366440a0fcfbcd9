// hovs' DDS stream: options and names, and over the loopback between two processes (inside a private network
// namespace: tests/hw/run_in_netns.sh), 100 consecutive bundles of images, camera models and point clouds
// received intact and decoded by a reader written from ROS 2's message definitions (tests/stream/cdr_reader.h).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <map>

#include "core/error.h"
#include "stream/dds.h"
#include "stream/publisher.h"
#include "stream/subscriber.h"
#include "tests/stream/cdr_reader.h"

namespace hovs::stream {
namespace {

DdsOptions Loopback(int domain) {
  DdsOptions o;
  o.domain = domain;
  o.interface = "lo";
  o.peers = {"127.0.0.1"};
  return o;
}

TEST(DdsOptions, RefuseWhatCycloneCannotUseNamingTheOption) {
  DdsOptions o;
  o.domain = 233;
  try {
    o.Check("");
    FAIL() << "domain 233 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "--domain");
    EXPECT_NE(e.message().find("0 .. 232"), std::string::npos) << e.what();
  }
  o.domain = -1;
  EXPECT_THROW(o.Check(""), Error);
  o.domain = 7, o.interface = "hovs-no-such-if";
  try {
    o.Check("");
    FAIL() << "a missing interface accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "--dds-interface");
    EXPECT_NE(e.message().find("lo"), std::string::npos) << "the interfaces the machine has are listed: " << e.what();
  }
  o.interface = "127.0.0.1";  // an address of lo
  EXPECT_NO_THROW(o.Check(""));
  o.peers = {"<Peer/>"};
  EXPECT_THROW(o.Check(""), Error);
  o.peers = {"127.0.0.1"};
  o.history = -1;
  EXPECT_THROW(o.Check(""), Error) << "a negative writer history accepted";
  o.history = 0;  // keep-all
  EXPECT_NO_THROW(o.Check(""));
}

TEST(DdsOptions, LoopbackConfigurationIsUnicastOnTheNamedInterface) {
  EXPECT_EQ(DdsConfigXml(DdsOptions()), "");
  const std::string xml = DdsConfigXml(Loopback(3));
  EXPECT_NE(xml.find("<NetworkInterface name=\"lo\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<Peer address=\"127.0.0.1\"/>"), std::string::npos) << xml;
  DdsOptions a;
  a.interface = "127.0.0.1";
  EXPECT_NE(DdsConfigXml(a).find("address=\"127.0.0.1\""), std::string::npos);
}

TEST(DdsNames, FollowRos2Conventions) {
  EXPECT_EQ(RosTopic("hovs", {"front", "image_raw"}), "/hovs/front/image_raw");
  EXPECT_EQ(RosTopic("/robot/hovs/", {"left-unit.view"}), "/robot/hovs/left_unit_view");
  EXPECT_EQ(RosTopic("hovs", {"3d"}), "/hovs/_3d");
  EXPECT_EQ(DdsTopic("/hovs/points"), "rt/hovs/points");
  EXPECT_EQ(RosTypeName(MessageType::kPointCloud2), "sensor_msgs/msg/PointCloud2");
}

// The content of bundle k, reproducible on both sides.
constexpr uint64_t kStamp0 = 1'765'000'000'123'456'789ull;
uint8_t Pixel(int k, int view, size_t i) { return static_cast<uint8_t>((k * 31 + view * 7 + i * 13) & 255); }
float Coord(int k, size_t i) { return static_cast<float>(0.5 + k + 0.001 * i); }

PublisherTopics TestTopics() {
  PublisherTopics t;
  unwrap::ViewSpec front;
  front.name = "front", front.width = 64, front.height = 48, front.hfov_deg = 60;
  t.images.push_back({"front", CameraInfoOfView(front), ""});
  t.images.push_back({"pano", std::nullopt, ""});
  t.cloud = true;
  return t;
}

Bundle TestBundle(int k) {
  Bundle b;
  b.stamp_ns = kStamp0 + uint64_t(k) * 100'000'000ull;
  b.images.resize(2);
  b.images[0] = {64, 48, 3, {}};
  b.images[1] = {200, 40, 1, {}};
  for (int v = 0; v < 2; ++v) {
    b.images[v].data.resize(size_t(b.images[v].width) * b.images[v].height * b.images[v].channels);
    for (size_t i = 0; i < b.images[v].data.size(); ++i) b.images[v].data[i] = Pixel(k, v, i);
  }
  b.cloud.width = 30, b.cloud.height = 2;
  for (size_t i = 0; i < 60 * 3; ++i) b.cloud.xyz.push_back(Coord(k, i));
  for (size_t i = 0; i < 60 * 3; ++i) b.cloud.rgb.push_back(static_cast<uint8_t>(i + k));
  return b;
}

// The publishing process: waits for the reader of every topic, then publishes 100 bundles (waiting for the writer
// thread: none dropped) and for the readers' acknowledgements, and reports through its exit code.
int PublishHundred(int domain) {
  try {
    DdsOptions o = Loopback(domain);
    o.history = 0, o.max_blocking_s = 10;  // every sample kept until acknowledged: a starved reader loses none
    Publisher pub(o, TestTopics());
    if (!pub.WaitForSubscribers(1, 30, /*camera_info=*/true)) return 3;  // every topic's reader, under load too
    for (int k = 0; k < 100; ++k) {
      Bundle b = TestBundle(k);
      pub.Offer(&b, true);
    }
    if (!pub.Flush(30)) return 4;  // written and acknowledged
    const PublishStats s = pub.Stats();
    return s.published == 100 && s.dropped == 0 ? 0 : 5;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "publisher: %s\n", e.what());
    return 6;
  }
}

TEST(DdsLoopback, AHundredBundlesCrossProcessesIntactInRos2Layout) {
  const int domain = 42;
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(PublishHundred(domain));

  const DdsOptions o = Loopback(domain);
  std::map<std::string, std::unique_ptr<Subscriber>> subs;
  subs["image"] = std::make_unique<Subscriber>(o, "/hovs/front/image_raw", MessageType::kImage, 256);
  subs["info"] = std::make_unique<Subscriber>(o, "/hovs/front/camera_info", MessageType::kCameraInfo, 256);
  subs["pano"] = std::make_unique<Subscriber>(o, "/hovs/pano/image_raw", MessageType::kImage, 256);
  subs["points"] = std::make_unique<Subscriber>(o, "/hovs/points", MessageType::kPointCloud2, 256);
  std::map<std::string, std::vector<std::vector<uint8_t>>> got;
  int idle = 0;
  while (idle < 400) {  // ends when every topic has 100 messages, or after 20 s without any
    bool any = false, all = true;
    for (auto& [name, s] : subs) {
      if (auto m = s->Take(0.0)) got[name].push_back(std::move(*m)), any = true;
      all = all && got[name].size() >= 100;
    }
    if (all) break;
    idle = any ? 0 : idle + 1;
    if (!any) usleep(50'000);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0) << "3: no reader matched; 4: not flushed or acknowledged; 5: dropped; 6: error";
  for (const char* t : {"image", "info", "pano", "points"}) ASSERT_EQ(got[t].size(), 100u) << t;

  for (int k = 0; k < 100; ++k) {
    const Bundle want = TestBundle(k);
    const uint64_t stamp = want.stamp_ns;
    for (int v = 0; v < 2; ++v) {
      const test::RosImage m = test::DecodeImage(got[v == 0 ? "image" : "pano"][k]);
      EXPECT_EQ(uint64_t(m.header.sec) * 1'000'000'000ull + m.header.nanosec, stamp) << "frame " << k;
      EXPECT_EQ(m.header.frame_id, v == 0 ? "hovs_front" : "hovs_pano");
      EXPECT_EQ(m.width, uint32_t(want.images[v].width));
      EXPECT_EQ(m.height, uint32_t(want.images[v].height));
      EXPECT_EQ(m.encoding, v == 0 ? "rgb8" : "mono8");
      EXPECT_EQ(m.is_bigendian, 0);
      EXPECT_EQ(m.step, uint32_t(want.images[v].width * want.images[v].channels));
      EXPECT_EQ(m.data, want.images[v].data) << "frame " << k << " view " << v;
      EXPECT_EQ(m.trailing, 0u);
    }
    const test::RosCameraInfo c = test::DecodeCameraInfo(got["info"][k]);
    EXPECT_EQ(uint64_t(c.header.sec) * 1'000'000'000ull + c.header.nanosec, stamp);
    EXPECT_EQ(c.width, 64u);
    EXPECT_EQ(c.height, 48u);
    EXPECT_EQ(c.distortion_model, "plumb_bob");
    EXPECT_EQ(c.d, std::vector<double>(5, 0.0));
    EXPECT_NEAR(c.k[0], 32 / std::tan(M_PI / 6), 1e-9);  // fx = (w / 2) / tan(hfov / 2)
    EXPECT_DOUBLE_EQ(c.k[2], 31.5);
    EXPECT_DOUBLE_EQ(c.k[5], 23.5);
    EXPECT_DOUBLE_EQ(c.k[8], 1.0);
    EXPECT_DOUBLE_EQ(c.r[4], 1.0);
    EXPECT_DOUBLE_EQ(c.p[0], c.k[0]);
    EXPECT_DOUBLE_EQ(c.p[10], 1.0);
    EXPECT_FALSE(c.do_rectify);
    EXPECT_EQ(c.trailing, 0u);
    const test::RosPointCloud2 p = test::DecodePointCloud2(got["points"][k]);
    EXPECT_EQ(uint64_t(p.header.sec) * 1'000'000'000ull + p.header.nanosec, stamp);
    EXPECT_EQ(p.width, 30u);
    EXPECT_EQ(p.height, 2u);
    ASSERT_EQ(p.fields.size(), 4u);
    const char* names[4] = {"x", "y", "z", "rgb"};
    for (int f = 0; f < 4; ++f) {
      EXPECT_EQ(p.fields[f].name, names[f]);
      EXPECT_EQ(p.fields[f].offset, uint32_t(4 * f));
      EXPECT_EQ(p.fields[f].datatype, 7);  // FLOAT32
      EXPECT_EQ(p.fields[f].count, 1u);
    }
    EXPECT_FALSE(p.is_bigendian);
    EXPECT_TRUE(p.is_dense);
    EXPECT_EQ(p.point_step, 16u);
    EXPECT_EQ(p.row_step, 16u * 30);
    ASSERT_EQ(p.data.size(), 60u * 16);
    for (size_t i = 0; i < 60; ++i) {
      float xyz[3];
      std::memcpy(xyz, &p.data[16 * i], 12);
      for (int a = 0; a < 3; ++a) EXPECT_EQ(xyz[a], want.cloud.xyz[3 * i + a]);
      EXPECT_EQ(p.data[16 * i + 12], want.cloud.rgb[3 * i + 2]);  // b, g, r, 0 as PCL packs rgb
      EXPECT_EQ(p.data[16 * i + 14], want.cloud.rgb[3 * i]);
    }
    EXPECT_EQ(p.trailing, 0u);
  }
}

// A reader that never takes, and one that goes away mid-run: the pipeline's Offer never waits, and every bundle
// is either published or counted as dropped.
TEST(DdsPublisher, SlowOrVanishingReadersNeverHoldThePipeline) {
  const DdsOptions o = Loopback(43);
  Publisher pub(o, TestTopics());
  Subscriber never_takes(o, "/hovs/front/image_raw", MessageType::kImage, 1);
  Subscriber info(o, "/hovs/front/camera_info", MessageType::kCameraInfo, 1);
  Subscriber pano(o, "/hovs/pano/image_raw", MessageType::kImage, 1);
  auto goes_away = std::make_unique<Subscriber>(o, "/hovs/points", MessageType::kPointCloud2, 1);
  ASSERT_TRUE(pub.WaitForSubscribers(1, 20)) << "no match in-process";
  for (int k = 0; k < 300; ++k) {
    Bundle b = TestBundle(k % 7);
    pub.Offer(&b);
    if (k == 150) goes_away.reset();
  }
  ASSERT_TRUE(pub.Flush(20));
  const PublishStats s = pub.Stats();
  EXPECT_EQ(s.offered, 300u);
  EXPECT_EQ(s.published + s.dropped + s.incomplete, 300u) << s.ToJson().dump();
  EXPECT_GT(s.published, 0u);
  EXPECT_EQ(s.write_errors, 0u);
}

TEST(DdsPublisher, RefusesBundlesThatDoNotMatchItsTopics) {
  Publisher pub(Loopback(44), TestTopics());
  Bundle b = TestBundle(0);
  b.images.pop_back();
  EXPECT_THROW(pub.Offer(&b), Error);
  b = TestBundle(0);
  b.images[0].width = 65;
  EXPECT_THROW(pub.Offer(&b), Error);  // its CameraInfo is 64 wide
  b = TestBundle(0);
  b.cloud.xyz.pop_back();
  EXPECT_THROW(pub.Offer(&b), Error);
}

}  // namespace
}  // namespace hovs::stream
