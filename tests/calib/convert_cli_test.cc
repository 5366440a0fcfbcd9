// hovs convert on a real calibration (the VMR reference corners): Kalibr's camchain of the unified model is the
// model itself (hovs compare reads it back: 0 px), the refits report their cost, bad input is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "core/io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

TEST(ConvertCli, WritesOtherToolsFilesAndRefusesBadInput) {
  const fs::path dir = test::Scratch("convert-cli", "vmr");
  const auto cal = test::Hovs("-q calibrate --corners " + std::string(HOVS_SHARED_DIR) +
                              "/data/vmr/reference_corners.csv --size 1024x768 --out " + (dir / "cal").string());
  ASSERT_EQ(cal.exit_code, 0) << cal.output;
  const std::string json = (dir / "cal" / "calibration.json").string();
  const auto kalibr = test::Hovs("-q convert " + json + " --kind unified --to kalibr --out " + (dir / "k").string());
  ASSERT_EQ(kalibr.exit_code, 0) << kalibr.output;
  const auto same = test::Hovs("-q compare " + (dir / "k" / "camchain.yaml").string() + " " + json +
                               " --kind-b unified --no-rotation --out " + (dir / "cmp").string());
  ASSERT_EQ(same.exit_code, 0) << same.output;
  EXPECT_LT(nlohmann::json::parse(ReadFile(dir / "cmp" / "compare.json"))["diff"]["px"]["max"].get<double>(), 1e-9);
  for (const std::string to : {"mei", "ds", "eucm", "kb"}) {
    const auto r = test::Hovs("-q convert " + json + " --kind polynomial --to " + to + " --out " + (dir / to).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto j = nlohmann::json::parse(ReadFile(dir / to / "convert.json"))["cameras"][0];
    EXPECT_FALSE(j["exact"].get<bool>());
    EXPECT_LT(j["refit"]["error_px"]["p95"].get<double>(), 0.1) << to;
    EXPECT_TRUE(fs::exists(dir / to / (to == "mei" ? "mei.yaml" : "camchain.yaml"))) << to;
  }
  // The MEI file is a model hovs reads: against the polynomial model it was refitted from, after the turn about
  // the axis that the polynomial model's affine terms hold and the refit reports.
  const auto mei = test::Hovs("-q compare " + (dir / "mei" / "mei.yaml").string() + " " + json +
                              " --kind-b polynomial --out " + (dir / "cmp-mei").string());
  ASSERT_EQ(mei.exit_code, 0) << mei.output;
  const auto cmp = nlohmann::json::parse(ReadFile(dir / "cmp-mei" / "compare.json"));
  EXPECT_LT(cmp["diff"]["px"]["p95"].get<double>(), 0.1);
  EXPECT_NEAR(cmp["diff"]["rotation_deg"].get<double>(),
              nlohmann::json::parse(ReadFile(dir / "mei" / "convert.json"))["cameras"][0]["refit"]["axis_rotation_deg"]
                  .get<double>(),
              0.01);
  // Two cameras and the relative pose of a stereo calibration: cam1 with T_cn_cnm1 in the tools' frames.
  WriteFileAtomic(dir / "stereo.json", R"({"right_from_left": {"q": [1, 0, 0, 0], "t": [-0.64, 0.007, 0.014]}})");
  const auto pair = test::Hovs("-q convert " + json + " --kind unified --right " + json + " --stereo " +
                               (dir / "stereo.json").string() + " --to kalibr --out " + (dir / "pair").string());
  ASSERT_EQ(pair.exit_code, 0) << pair.output;
  const std::string chain = ReadFile(dir / "pair" / "camchain.yaml");
  EXPECT_NE(chain.find("cam1:\n  T_cn_cnm1:"), std::string::npos) << chain;
  EXPECT_NE(chain.find("- [0, 0, 1, -0.014"), std::string::npos) << "z flips with the frame: " << chain;
  // Basalt's calibration file: the double-sphere refit under Basalt's names, cam1 placed by the stereo pose.
  const auto basalt = test::Hovs("-q convert " + json + " --kind polynomial --right " + json + " --stereo " +
                                 (dir / "stereo.json").string() + " --to basalt --out " + (dir / "b").string());
  ASSERT_EQ(basalt.exit_code, 0) << basalt.output;
  const auto bj = nlohmann::json::parse(ReadFile(dir / "b" / "basalt_calib.json"))["value0"];
  const auto refit = nlohmann::json::parse(ReadFile(dir / "b" / "convert.json"))["cameras"][0]["refit"]["parameters"];
  ASSERT_EQ(bj["intrinsics"].size(), 2u);
  EXPECT_EQ(bj["intrinsics"][0]["camera_type"], "ds");
  for (const char* k : {"fx", "fy", "cx", "cy", "xi", "alpha"})
    EXPECT_EQ(bj["intrinsics"][0]["intrinsics"][k].get<double>(), refit[k].get<double>()) << k;
  EXPECT_EQ(bj["T_imu_cam"][0]["qw"].get<double>(), 1.0);
  // cam1's centre in cam0's frame: the baseline, 0.64 m.
  const double bx = bj["T_imu_cam"][1]["px"], by = bj["T_imu_cam"][1]["py"], bz = bj["T_imu_cam"][1]["pz"];
  EXPECT_NEAR(std::sqrt(bx * bx + by * by + bz * bz), std::sqrt(0.64 * 0.64 + 0.007 * 0.007 + 0.014 * 0.014), 1e-9);
  for (const char* key : {"resolution", "vignette", "calib_accel_bias", "calib_gyro_bias", "imu_update_rate",
                          "T_mocap_world", "T_imu_marker", "cam_time_offset_ns"})
    EXPECT_TRUE(bj.contains(key)) << key << ": every field Basalt's reader expects";
  // OpenCV's file, and the omni_calibration sample's (no image size: --image-size gives it).
  const auto omnidir = test::Hovs("-q convert " + json + " --kind unified --to omnidir --out " + (dir / "o").string());
  ASSERT_EQ(omnidir.exit_code, 0) << omnidir.output;
  std::string text = ReadFile(dir / "o" / "unified.yaml");
  const size_t w0 = text.find("image_width: "), h1 = text.find('\n', text.find("image_height: "));
  ASSERT_NE(w0, std::string::npos);
  const std::string size_lines = text.substr(w0, h1 + 1 - w0);
  int width = 0, height = 0;
  ASSERT_EQ(std::sscanf(size_lines.c_str(), "image_width: %d\nimage_height: %d", &width, &height), 2);
  text.erase(w0, h1 + 1 - w0);
  WriteFileAtomic(dir / "nosize.yaml", text);
  const auto sized =
      test::Hovs("-q convert " + (dir / "nosize.yaml").string() + " --to omnidir --image-size " +
                 std::to_string(width) + "x" + std::to_string(height) + " --out " + (dir / "o2").string());
  ASSERT_EQ(sized.exit_code, 0) << sized.output;
  const auto back = test::Hovs("-q compare " + (dir / "o2" / "unified.yaml").string() + " " + json +
                               " --kind-b unified --no-rotation --out " + (dir / "cmp-o").string());
  ASSERT_EQ(back.exit_code, 0) << back.output;
  EXPECT_LT(nlohmann::json::parse(ReadFile(dir / "cmp-o" / "compare.json"))["diff"]["px"]["max"].get<double>(), 1e-9);
  const auto refused = [&](const std::string& args, const std::string& needle) {
    const auto r = test::Hovs(args + " --out " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  refused("convert " + json + " --to colmap", "expected kalibr, mei, omnidir, ds, eucm, kb or basalt");
  refused("convert " + json + " --right " + json + " --to kalibr", "needs both --right and --stereo");
  refused("convert " + json + " --right " + json + " --stereo " + json + " --to kalibr", "no right_from_left");
  refused("convert " + (dir / "missing.json").string() + " --to ds", "file not found");
  refused("convert " + (dir / "nosize.yaml").string() + " --to kalibr", "has no image_width / image_height");
  refused("convert " + json + " --image-size 640x --to ds", "--image-size: expected WxH");
  refused("convert " + (dir / "ds" / "camchain.yaml").string() + " --to mei", "hovs reads Kalibr's omni model");
}

}  // namespace
}  // namespace hovs
