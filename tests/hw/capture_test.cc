// Capture through a real GigE Vision peer: Aravis' camera simulator in process, on the loopback of a network
// namespace of our own (tests/hw/run_in_netns.sh), serving frames whose every byte is known.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "hw/camera_source.h"
#include "hw/fake_gige.h"

namespace hovs::hw {
namespace {

std::vector<FakeFrame> RandomFrames(int n, int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<FakeFrame> out(n);
  for (auto& f : out) {
    f.width = w, f.height = h;
    f.data.resize(size_t(w) * h);
    for (auto& b : f.data) b = static_cast<uint8_t>(rng());
  }
  return out;
}

CaptureSettings Settings() {
  CaptureSettings s;
  s.pixel_format = "Mono8";
  s.buffers = 8;
  return s;
}

TEST(GigECapture, FramesCrossTheProtocolByteForByte) {
  FakeGigECamera sim("127.0.0.1", "HOVS-SIM-1", RandomFrames(3, 688, 550, 1));
  auto cam = OpenAravisCamera("127.0.0.1", Settings());
  const auto info = cam->Info();
  EXPECT_EQ(info["serial"], "HOVS-SIM-1");
  EXPECT_EQ(info["region"], nlohmann::json({0, 0, 688, 550}));
  cam->Start();
  // The stream socket is sized before the first frame: Aravis 0.8 sizes it only when that frame's first packet
  // arrives, and with the system's default buffer the simulator's first frame (a burst on the loopback) lost
  // packets on every run (hw/aravis_camera.cc, PresizeStreamSocket).
  EXPECT_EQ(cam->Info()["stream_socket_presized"], true);
  int complete = 0;
  uint64_t last_ns = 0;
  for (int k = 0; k < 12; ++k) {
    const auto f = cam->Grab(3.0);
    ASSERT_TRUE(f.has_value()) << "no frame within 3 s";
    // The first frame must arrive whole (it did not before the socket was sized in advance). A later frame may
    // still be lost if the receiving thread stalls for long on a loaded machine (UDP; the simulator does not
    // resend): such a frame must be reported incomplete, never passed on as good, and counted, and at most one
    // may be. Every frame reported complete must be the frame that was sent, byte for byte.
    if (!f->complete) {
      ASSERT_GT(k, 0) << "the first frame arrived incomplete: " << f->status;
      EXPECT_NE(f->status, "success") << "frame " << k;
      continue;
    }
    ASSERT_EQ(f->width, 688);
    ASSERT_EQ(f->height, 550);
    EXPECT_EQ(f->data, sim.ServedFrame(FakeGigECamera::Stamp(f->data)))
        << "frame " << k << " differs from what was sent";
    EXPECT_GT(f->device_ns, last_ns);
    last_ns = f->device_ns;
    ++complete;
  }
  cam->Stop();
  EXPECT_GE(complete, 11) << "more than one of twelve frames incomplete on a loopback";
  const auto st = cam->Stats();
  EXPECT_GE(st.completed, static_cast<uint64_t>(complete));  // the stream may complete more before Stop
  EXPECT_EQ(st.incomplete_seen, static_cast<uint64_t>(12 - complete));
}

TEST(GigECapture, WithOnePercentPacketLossEveryFrameIsCompleteAndIdenticalOrCounted) {
  // 256 x 200 bytes are about 37 packets: with 1 % loss about 69 % of the frames arrive whole (Aravis' simulator
  // does not resend), so 40 frames give both kinds with near certainty.
  FakeGigECamera sim("127.0.0.1", "HOVS-SIM-LOSS", RandomFrames(2, 256, 200, 2), 0.01);
  auto s = Settings();
  auto cam = OpenAravisCamera("127.0.0.1", s);
  cam->Start();
  int complete = 0, incomplete = 0;
  for (int k = 0; k < 40; ++k) {
    const auto f = cam->Grab(3.0);
    ASSERT_TRUE(f.has_value());
    if (!f->complete) {
      ++incomplete;
      continue;
    }
    ++complete;
    EXPECT_EQ(f->data, sim.ServedFrame(FakeGigECamera::Stamp(f->data))) << "a frame reported complete is corrupt";
  }
  cam->Stop();
  const auto st = cam->Stats();
  std::printf(
      "[ figure ] 1 %% GVSP loss, 256 x 200 Mono8: %d complete, %d incomplete; %llu packets missing, %llu resent\n",
      complete, incomplete, static_cast<unsigned long long>(st.missing_packets),
      static_cast<unsigned long long>(st.resent_packets));
  EXPECT_EQ(st.incomplete_seen, static_cast<uint64_t>(incomplete));
  EXPECT_GT(st.missing_packets + st.resent_packets, 0u) << "the simulator's loss did not happen";
  EXPECT_GT(incomplete, 0);
  EXPECT_GT(complete, 0);
}

TEST(GigECapture, TwoCamerasOnTwoLoopbackAddressesArePairedByTimestamp) {
  FakeGigECamera left("127.0.0.1", "HOVS-SIM-L", RandomFrames(2, 344, 275, 3));
  FakeGigECamera right("127.0.0.2", "HOVS-SIM-R", RandomFrames(2, 344, 275, 4));
  auto cl = OpenAravisCamera("127.0.0.1", Settings());
  auto cr = OpenAravisCamera("127.0.0.2", Settings());
  EXPECT_EQ(cl->Info()["serial"], "HOVS-SIM-L");
  EXPECT_EQ(cr->Info()["serial"], "HOVS-SIM-R");
  cl->Start();
  cr->Start();
  // Both simulators run at 25 fps from their own clocks, started within a few ms: pairs within half a period.
  FramePairer pairer;
  pairer.tolerance_ns = 20'000'000;
  int pairs = 0;
  for (int k = 0; k < 30 && pairs < 8; ++k) {
    for (int c = 0; c < 2; ++c) {
      auto f = (c == 0 ? cl : cr)->Grab(3.0);
      ASSERT_TRUE(f.has_value());
      ASSERT_TRUE(f->complete) << f->status;
      EXPECT_EQ(f->data, (c == 0 ? left : right).ServedFrame(FakeGigECamera::Stamp(f->data)));
      for (const auto& [a, b] : pairer.Add(c, std::move(*f))) {
        const uint64_t dt = a.device_ns > b.device_ns ? a.device_ns - b.device_ns : b.device_ns - a.device_ns;
        EXPECT_LE(dt, pairer.tolerance_ns);
        ++pairs;
      }
    }
  }
  EXPECT_GE(pairs, 8);
}

TEST(GigECapture, BadInputIsOneClearError) {
  FakeGigECamera sim("127.0.0.1", "HOVS-SIM-BAD", RandomFrames(1, 64, 48, 5));
  auto s = Settings();
  s.pixel_format = "RGB10";
  try {
    OpenAravisCamera("127.0.0.1", s);
    FAIL() << "an unsupported pixel format was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported pixel format 'RGB10'"), std::string::npos) << e.what();
  }
  s = Settings();
  s.width = 4000;
  EXPECT_THROW(OpenAravisCamera("127.0.0.1", s), Error);
  s = Settings();
  s.features = {{"NoSuchFeature", "1"}};
  try {
    OpenAravisCamera("127.0.0.1", s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no GenICam feature 'NoSuchFeature'"), std::string::npos) << e.what();
  }
  try {
    OpenAravisCamera("127.0.0.9", Settings());
    FAIL() << "a missing camera was opened";
  } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos) << e.what(); }
  // Grab times out cleanly when the camera waits for a trigger that never comes.
  s = Settings();
  s.trigger = "software";
  auto cam = OpenAravisCamera("127.0.0.1", s);
  cam->Start();
  EXPECT_FALSE(cam->Grab(0.3).has_value());
  cam->SoftwareTrigger();
  const auto f = cam->Grab(3.0);
  ASSERT_TRUE(f.has_value());
  EXPECT_TRUE(f->complete);
  cam->Stop();
}

TEST(FramePairer, PairsWithinToleranceAndCountsTheRest) {
  FramePairer p;
  p.tolerance_ns = 1000;
  auto fr = [](uint64_t t) {
    Frame f;
    f.device_ns = t;
    return f;
  };
  EXPECT_TRUE(p.Add(0, fr(10'000)).empty());
  EXPECT_EQ(p.Add(1, fr(10'500)).size(), 1u);
  EXPECT_TRUE(p.Add(0, fr(20'000)).empty());
  EXPECT_TRUE(p.Add(1, fr(25'000)).empty());  // too far from 20'000
  EXPECT_TRUE(p.Add(0, fr(30'000)).empty());
  const auto pr = p.Add(1, fr(30'200));
  ASSERT_EQ(pr.size(), 1u);
  EXPECT_EQ(pr[0].first.device_ns, 30'000u);
  EXPECT_EQ(pr[0].second.device_ns, 30'200u);
  EXPECT_EQ(p.dropped, 2u);  // 20'000 and 25'000
}

}  // namespace
}  // namespace hovs::hw
