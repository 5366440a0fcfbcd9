// hovs capture end to end over the GigE Vision protocol: rendered frames served by Aravis' simulator, captured
// into a dataset, then calibrated and unwrapped by the same commands as synthetic data. Runs inside a private
// network namespace (tests/hw/run_in_netns.sh).
#include <gtest/gtest.h>

#include <chrono>

#include <nlohmann/json.hpp>

#include "core/io.h"
#include "raytrace/render.h"
#include "scenes/dataset.h"
#include "tests/cli_helper.h"
#include "io/image_io.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

std::vector<uint8_t> Grey8(const fs::path& p, int* w, int* h) {
  int c = 0;
  const auto px = io::ReadImage(p, w, h, &c);
  std::vector<uint8_t> out(size_t(*w) * *h);
  for (size_t k = 0; k < out.size(); ++k) {
    const auto b = [&](int ch) { return static_cast<int>(std::lround(std::clamp(px[k * c + ch], 0.f, 1.f) * 255)); };
    out[k] = c == 1 ? b(0) : static_cast<uint8_t>((299 * b(0) + 587 * b(1) + 114 * b(2) + 500) / 1000);
  }
  return out;
}

uint64_t Stamp(const std::vector<uint8_t>& d) {
  uint64_t k = 0;
  for (int i = 0; i < 8; ++i) k |= uint64_t(d[i]) << (8 * i);
  return k;
}

TEST(CaptureCli, RenderedFramesCrossTheProtocolIntoADatasetThatCalibratesAndUnwraps) {
  const fs::path dir = test::Scratch("capture-cli", "work");
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
  scenes::DownscaleCameras(&cfg, 2);
  cfg.render.samples = 2;
  scenes::DatasetOptions o;
  o.count = 5;
  scenes::WriteCalibrationDataset(cfg, o, dir / "set", {{"hovs", "test"}});

  const auto cap = test::Hovs("-q capture --simulate " + (dir / "set/dataset.json").string() + " --frames 5 --out " +
                              (dir / "cap").string());
  ASSERT_EQ(cap.exit_code, 0) << cap.output;
  const auto m = nlohmann::json::parse(ReadFile(dir / "cap/dataset.json"));
  EXPECT_EQ(m["format"], "hovs-dataset");
  EXPECT_EQ(m["kind"], "capture");
  EXPECT_EQ(m["status"], "complete");
  ASSERT_EQ(m["frames"].size(), 5u);
  EXPECT_EQ(m["units"][0]["camera"]["serial"], "HOVS-SIM-unit0");
  EXPECT_TRUE(m["statistics"]["unit0"].contains("missing_packets"));
  const auto src = nlohmann::json::parse(ReadFile(dir / "set/dataset.json"));
  uint64_t last = 0;
  for (const auto& fr : m["frames"]) {
    const auto& v = fr["views"][0];
    EXPECT_FALSE(v.contains("ground_truth"));
    EXPECT_GT(v["device_ns"].get<uint64_t>(), last);
    last = v["device_ns"];
    // Byte for byte: the captured image is the served frame (the rendered image in grey, first 8 bytes = stamp).
    int w = 0, h = 0, ws = 0, hs = 0;
    auto got = Grey8(dir / "cap" / v["image"].get<std::string>(), &w, &h);
    const uint64_t k = Stamp(got);
    // Nothing is lost at the start: the first frame written is the first one the simulator served.
    if (&fr == &m["frames"][0]) { EXPECT_EQ(k, 0u) << "the first captured frame is served frame " << k; }
    auto sent = Grey8(dir / "set" / src["frames"][k % 5]["views"][0]["image"].get<std::string>(), &ws, &hs);
    ASSERT_EQ(w, ws);
    for (int i = 0; i < 8; ++i) sent[i] = static_cast<uint8_t>(k >> (8 * i));
    EXPECT_TRUE(got == sent) << "captured frame " << fr["id"] << " differs from served frame " << k;
  }
  // Uncompressed PGM (for full frame rates): the same bytes, read by the same loaders.
  const auto pgm = test::Hovs("-q capture --simulate " + (dir / "set/dataset.json").string() +
                              " --frames 3 --image-format pgm --out " + (dir / "cap-pgm").string());
  ASSERT_EQ(pgm.exit_code, 0) << pgm.output;
  const auto mp = nlohmann::json::parse(ReadFile(dir / "cap-pgm/dataset.json"));
  ASSERT_EQ(mp["frames"].size(), 3u);
  for (const auto& fr : mp["frames"]) {
    const auto& v = fr["views"][0];
    EXPECT_EQ(fs::path(v["image"].get<std::string>()).extension(), ".pgm");
    int w = 0, h = 0, ws = 0, hs = 0;
    auto got = Grey8(dir / "cap-pgm" / v["image"].get<std::string>(), &w, &h);
    const uint64_t k = Stamp(got);
    auto sent = Grey8(dir / "set" / src["frames"][k % 5]["views"][0]["image"].get<std::string>(), &ws, &hs);
    ASSERT_EQ(w, ws);
    for (int i = 0; i < 8; ++i) sent[i] = static_cast<uint8_t>(k >> (8 * i));
    EXPECT_TRUE(got == sent) << "PGM frame " << fr["id"] << " differs from served frame " << k;
  }
  // The same calibration and expansion code as for synthetic data.
  const auto cal = test::Hovs("-q calibrate --dataset " + (dir / "cap/dataset.json").string() +
                              " --board 7x5x0.03 --out " + (dir / "cal").string());
  ASSERT_EQ(cal.exit_code, 0) << cal.output;
  const auto c = nlohmann::json::parse(ReadFile(dir / "cal/calibration.json"));
  for (const auto& d : c["detection"]) EXPECT_TRUE(d["complete"].get<bool>()) << d.dump();
  EXPECT_LT(c["polynomial"]["rms_px"].get<double>(), 0.3);
  const auto uw =
      test::Hovs("-q unwrap --model " + (dir / "cal/calibration.json").string() + " --layout article --input " +
                 (dir / "cap/dataset.json").string() + " --out " + (dir / "views").string());
  ASSERT_EQ(uw.exit_code, 0) << uw.output;
  EXPECT_EQ(nlohmann::json::parse(ReadFile(dir / "views/views.json"))["frames"].size(), 5u);

  // hovs live: frames over the protocol -> the six views, written every 5th frame, latency figures.
  const auto live = test::Hovs("-q live --simulate " + (dir / "set/dataset.json").string() + " --model " +
                               (dir / "cal/calibration.json").string() + " --frames 10 --write-every 5 --out " +
                               (dir / "live").string());
  ASSERT_EQ(live.exit_code, 0) << live.output;
  const auto lj = nlohmann::json::parse(ReadFile(dir / "live/live.json"));
  EXPECT_EQ(lj["frames_processed"], 10);
  EXPECT_EQ(lj["views"], 6);
  EXPECT_EQ(lj["frames_written"], 2);
  EXPECT_GT(lj["latency"]["remap"]["median_ms"].get<double>(), 0.0);
  for (const char* f : {"frame000000_view0.png", "frame000005_view300.png"})
    EXPECT_TRUE(fs::exists(dir / "live" / f)) << f;
  const auto live_replay = test::Hovs("-q live --replay " + (dir / "cap/dataset.json").string() + " --model " +
                                      (dir / "cal/calibration.json").string() + " --frames 3");
  EXPECT_EQ(live_replay.exit_code, 0) << live_replay.output;
  const auto live_bad = test::Hovs("live --replay " + (dir / "cap/dataset.json").string() + " --model " +
                                   (dir / "cal/calibration.json").string() + " --pixel-format Mono16 --frames 3");
  EXPECT_EQ(live_bad.exit_code, 2);
  EXPECT_NE(live_bad.output.find("Mono8 or BayerRG8"), std::string::npos) << live_bad.output;
  // A NaN frame timeout reached Aravis and aborted in a GLib assertion: now named, exit 2, nothing written.
  const auto live_nan = test::Hovs("live --simulate " + (dir / "set/dataset.json").string() + " --model " +
                                   (dir / "cal/calibration.json").string() + " --frames 2 --timeout nan -o " +
                                   (dir / "live-nan").string());
  EXPECT_EQ(live_nan.exit_code, 2) << live_nan.output;
  EXPECT_NE(live_nan.output.find("--timeout"), std::string::npos) << live_nan.output;
  EXPECT_FALSE(fs::exists(dir / "live-nan"));

  // 1 % packet loss (the simulator does not resend; at 1375 x 1100, about 1000 packets a frame, few frames
  // survive): nothing corrupt is written, incomplete frames are listed, the time limit ends the capture; when no
  // frame survived at all, the capture ends with one error line and a manifest whose status says so.
  const auto lossy =
      test::Hovs("-q capture --simulate " + (dir / "set/dataset.json").string() +
                 " --simulate-loss 0.01 --frames 2 --seconds 4 --timeout 10 --out " + (dir / "lossy").string());
  if (lossy.exit_code != 0) {
    // No complete frame in the time: one error, and no folder left (a good capture into it must not be refused).
    EXPECT_EQ(lossy.exit_code, 2) << lossy.output;
    EXPECT_NE(lossy.output.find("no complete frame"), std::string::npos) << lossy.output;
    EXPECT_EQ(std::count(lossy.output.begin(), lossy.output.end(), '\n'), 1) << lossy.output;
    EXPECT_FALSE(fs::exists(dir / "lossy"));
  }
  const auto ml = lossy.exit_code == 0
                      ? nlohmann::json::parse(ReadFile(dir / "lossy/dataset.json"))
                      : nlohmann::json{{"incomplete_frames", {1}}, {"frames", nlohmann::json::array()}};
  EXPECT_GT(ml["incomplete_frames"].size(), 0u);
  for (const auto& fr : ml["frames"]) {
    int w = 0, h = 0, ws = 0, hs = 0;
    auto got = Grey8(dir / "lossy" / fr["views"][0]["image"].get<std::string>(), &w, &h);
    const uint64_t k = Stamp(got);
    auto sent = Grey8(dir / "set" / src["frames"][k % 5]["views"][0]["image"].get<std::string>(), &ws, &hs);
    for (int i = 0; i < 8; ++i) sent[i] = static_cast<uint8_t>(k >> (8 * i));
    EXPECT_TRUE(got == sent) << "a frame written under packet loss is corrupt";
  }

  // Every frame incomplete (49 % of the packets dropped): the wait is bounded overall, not per frame. The capture
  // ends after --timeout without a complete frame, with one error line and a manifest whose status says so.
  const auto t_hang = std::chrono::steady_clock::now();
  const auto hang = test::Run("timeout -s KILL 60 " + std::string(HOVS_BINARY) + " -q capture --simulate " +
                              (dir / "set/dataset.json").string() +
                              " --simulate-loss 0.49 --frames 1 --timeout 3 --out " + (dir / "hang").string());
  EXPECT_EQ(hang.exit_code, 2) << hang.output;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t_hang).count(), 30);
  EXPECT_NE(hang.output.find("no complete frame within 3 s"), std::string::npos) << hang.output;
  // Nothing was captured: nothing is left, so that the same command can run again into the folder.
  EXPECT_FALSE(fs::exists(dir / "hang"));

  // Ctrl-C ends the capture with a valid manifest.
  const auto intr =
      test::Run("timeout -s INT --preserve-status 4 " + std::string(HOVS_BINARY) + " -q capture --simulate " +
                (dir / "set/dataset.json").string() + " --frames 100000 --out " + (dir / "intr").string());
  EXPECT_EQ(intr.exit_code, 0) << intr.output;
  const auto mi = nlohmann::json::parse(ReadFile(dir / "intr/dataset.json"));
  EXPECT_NE(mi["status"].get<std::string>().find("interrupted"), std::string::npos) << mi["status"];
  for (const auto& fr : mi["frames"])
    EXPECT_TRUE(fs::exists(dir / "intr" / fr["views"][0]["image"].get<std::string>()));

  // A full disk (simulated by a file-size limit: a write beyond it fails with EFBIG instead of killing the
  // process): one clear error, exit 2, and nothing left (no frame was captured; no partial image), so that the
  // same command can run again into the folder.
  const auto full = test::Run("bash -c 'ulimit -f 1000; trap \"\" XFSZ; exec " + std::string(HOVS_BINARY) +
                              " -q capture --simulate " + (dir / "set/dataset.json").string() +
                              " --frames 3 --image-format pgm --out " + (dir / "full").string() + "'");
  EXPECT_EQ(full.exit_code, 2) << full.output;
  EXPECT_NE(full.output.find("write failed (disk full?)"), std::string::npos) << full.output;
  EXPECT_FALSE(fs::exists(dir / "full"));

  // Bad input: one clear error, exit 2.
  const auto rejected = [&](const std::string& args, const std::string& needle) {
    const auto r = test::Hovs("capture " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
  };
  rejected("--camera 127.0.0.9 --out " + (dir / "none").string(), "not found");
  rejected("--simulate " + (dir / "set/dataset.json").string() + " --camera x --out " + (dir / "none").string(),
           "exactly one of");
  rejected(
      "--simulate " + (dir / "set/dataset.json").string() + " --pixel-format RGB10 --out " + (dir / "none").string(),
      "unsupported pixel format");
  rejected("--simulate " + (dir / "set/dataset.json").string() + " --out " + (dir / "cap").string(), "not empty");
  rejected("--simulate " + (dir / "set/dataset.json").string() + " --timeout nan --out " + (dir / "none").string(),
           "--timeout");
  EXPECT_FALSE(fs::exists(dir / "none"));
  fs::remove_all(dir.parent_path());
}

TEST(CaptureCli, StereoPairFromTwoSimulatorsIsPairedByTimestamp) {
  const fs::path dir = test::Scratch("capture-cli", "stereo");
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  scenes::DownscaleCameras(&cfg, 5);  // 550 x 440
  cfg.render.samples = 1;
  scenes::DatasetOptions o = scenes::DatasetOptions::ForKind("stereo_aruco");
  o.count = 2;
  scenes::WriteCalibrationDataset(cfg, o, dir / "set", {{"hovs", "test"}});
  const auto cap = test::Hovs("-q capture --simulate " + (dir / "set/dataset.json").string() + " --frames 4 --out " +
                              (dir / "cap").string());
  ASSERT_EQ(cap.exit_code, 0) << cap.output;
  const auto m = nlohmann::json::parse(ReadFile(dir / "cap/dataset.json"));
  ASSERT_EQ(m["frames"].size(), 4u);
  EXPECT_EQ(m["units"][0]["camera"]["id"], "127.0.0.1");
  EXPECT_EQ(m["units"][1]["camera"]["id"], "127.0.0.2");
  for (const auto& fr : m["frames"]) {
    ASSERT_EQ(fr["views"].size(), 2u);
    EXPECT_EQ(fr["views"][0]["unit"], "left");
    EXPECT_EQ(fr["views"][1]["unit"], "right");
    const auto a = fr["views"][0]["device_ns"].get<uint64_t>(), b = fr["views"][1]["device_ns"].get<uint64_t>();
    EXPECT_LE(a > b ? a - b : b - a, 20'000'000u);
  }
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace hovs
