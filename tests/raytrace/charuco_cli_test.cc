// A ChArUco board for monocular calibration: a rendered set of the reference unit with a ChArUco board and the
// same set (same seed, so the same poses) with the checkerboard of the same squares, each detected by hovs and
// calibrated; the ChArUco result within 0.05 px of the checkerboard's.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "calib/checkerboard_detector.h"
#include "core/error.h"
#include "core/io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

TEST(CharucoSpec, ParsesAndRefusesBadBoards) {
  const calib::CharucoSpec s = calib::ParseCharucoSpec("charuco:8x6x0.03x0.022", "--board");
  EXPECT_EQ(s.squares_x, 8);
  EXPECT_EQ(s.squares_y, 6);
  EXPECT_DOUBLE_EQ(s.marker, 0.022);
  EXPECT_EQ(s.dictionary, "DICT_4X4_250");
  EXPECT_EQ(calib::ParseCharucoSpec("charuco:5x5x0.04x0.03:DICT_6X6_250", "--board").dictionary, "DICT_6X6_250");
  // Corner 0 is the top-left inner corner as printed: left of the centre, above it (y up the print).
  EXPECT_NEAR(s.CornerXY(0).x(), -0.09, 1e-12);
  EXPECT_NEAR(s.CornerXY(0).y(), 0.06, 1e-12);
  EXPECT_NEAR(s.CornerXY(8).x(), -0.06, 1e-12);  // row 1, column 1
  EXPECT_NEAR(s.CornerXY(8).y(), 0.03, 1e-12);
  for (const char* bad : {"charuco:8x6", "charuco:8x6x0.03x0.04", "charuco:2x6x0.03x0.02", "charuco:8x6x0.03x0.02:NOPE",
                          "charuco:8x6x0.03x0.02x7", "charuco:40x40x0.03x0.02:DICT_4X4_50"})
    EXPECT_THROW(calib::ParseCharucoSpec(bad, "--board"), Error) << bad;
}

TEST(CalibrateCli, ACharucoSetCalibratesLikeTheCheckerboardSet) {
  const fs::path dir = test::Scratch("calibrate-cli", "charuco");
  const std::string scene = std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml";
  const auto render = [&](const std::string& board, const std::string& name) {
    const auto r = test::Hovs("-q dataset --scene " + scene + " --board " + board + " -n 8 --seed 5 --truth none -o " +
                              (dir / name).string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
  };
  render("charuco:8x6x0.03x0.022", "charuco");
  render("7x5x0.03", "checker");
  const auto calibrate = [&](const std::string& name) {
    const auto r = test::Hovs("-q calibrate --dataset " + (dir / name / "dataset.json").string() + " --out " +
                              (dir / (name + "-cal")).string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(ReadFile(dir / (name + "-cal") / "calibration.json"));
  };
  const auto ch = calibrate("charuco"), ck = calibrate("checker");
  int found = 0, corners = 0;
  for (const auto& d : ch["detection"]) found += d["found"].get<bool>(), corners += d["corners"].get<int>();
  const double ch_rms = ch["polynomial"]["rms_px"], ck_rms = ck["polynomial"]["rms_px"];
  std::printf(
      "[ figure ] charuco: %d of 8 boards, %d corners, %.4f px from the exact corners, polynomial %.4f px (checker "
      "%.4f px), ray error %.4f deg (checker %.4f deg)\n",
      found, corners, ch["detection_rms_to_truth_px"].get<double>(), ch_rms, ck_rms,
      ch["ground_truth"]["mean_ray_angle_deg"].get<double>(), ck["ground_truth"]["mean_ray_angle_deg"].get<double>());
  EXPECT_GE(found, 7);
  EXPECT_EQ(ch["input"]["corners"], "hovs ChArUco detector");
  EXPECT_LT(ch["detection_rms_to_truth_px"].get<double>(), 0.06);
  EXPECT_LT(std::abs(ch_rms - ck_rms), 0.05);
  EXPECT_LT(ch["ground_truth"]["mean_ray_angle_deg"].get<double>(), 0.08);
  // Bad ChArUco input: one clear error each, exit 2, nothing written.
  const auto refused = [&](const std::string& args, const std::string& needle) {
    const auto r = test::Hovs(args + " --out " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  const std::string images = (dir / "charuco" / "images").string();
  refused("calibrate --images " + images + " --board charuco:8x6x0.03x0.03", "the marker must be smaller");
  refused("calibrate --images " + images + " --board charuco:8x6x0.03x0.022:DICT_6X6_250", "usable board");
  refused("dataset --scene " + scene + " --board charuco:8x6x0.03 -n 2", "expected charuco:SXxSYxSQUARExMARKER");
}

}  // namespace
}  // namespace hovs
