// hovs stereo-calibrate and hovs depth from the command line, on rendered datasets: the relative pose from three
// ArUco pairs (detection in unwrapped views, joint solve) against the true rig, depth of a street frame against
// its range channel, and bad input (a single-unit dataset): one error, exit 2, no output.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {

namespace fs = std::filesystem;
using test::Hovs;

std::string Src(const std::string& rel) { return std::string(HOVS_SOURCE_DIR) + "/" + rel; }

TEST(StereoCli, CalibratesRenderedPairsAndComputesDepth) {
  const fs::path dir = test::Scratch("depth-cli", "run");
  const auto set = Hovs("--quiet dataset --kind stereo_aruco --scene " + Src("scenes/reference_stereo.yaml") +
                        " --count 3 --samples 1 --seed 2 -o " + (dir / "stereo").string());
  ASSERT_EQ(set.exit_code, 0) << set.output;
  const auto cal = Hovs("--quiet stereo-calibrate --dataset " + (dir / "stereo/dataset.json").string() + " -o " +
                        (dir / "cal").string());
  ASSERT_EQ(cal.exit_code, 0) << cal.output;
  const auto j = nlohmann::json::parse(ReadFile(dir / "cal/stereo.json"));
  const double b_err = std::abs(j["ground_truth"]["baseline_error_mm"].get<double>());
  const double r_err = j["ground_truth"]["rotation_error_deg"].get<double>();
  std::printf(
      "[ figure ] stereo-calibrate, 3 rendered pairs (1 spp): baseline error %.3f mm, rotation error %.4f deg, "
      "RMS %.3f px\n",
      b_err, r_err, j["rms_px"].get<double>());
  EXPECT_LE(b_err, 1.0);  // 3 pairs only; the 12-pair figure is in the notes and README
  EXPECT_LE(r_err, 0.05);
  EXPECT_TRUE(fs::exists(dir / "cal/stereo.yaml"));
  EXPECT_NE(ReadFile(dir / "cal/stereo.yaml").find("baseline"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "cal/figures/frame0_left.png"));  // reprojection figure per pair and unit
  EXPECT_EQ(j["corner_refinement"], "edges");
  for (const auto& det : j["detections"])  // at 1 spp most corners still come from the markers' edges
    EXPECT_GE(det["left_from_edges"].get<double>(), 0.5 * det["left_corners"].get<double>()) << det.dump();
  // An unknown corner refinement: one error naming the option, nothing written.
  const auto badref = Hovs("stereo-calibrate --dataset " + (dir / "stereo/dataset.json").string() +
                           " --corner-refinement lines -o " + (dir / "badref").string());
  EXPECT_NE(badref.exit_code, 0);
  EXPECT_NE(badref.output.find("--corner-refinement"), std::string::npos) << badref.output;
  EXPECT_FALSE(fs::exists(dir / "badref"));
  // Options out of range: named, before any detection ("bad options" once, or a negative marker check taken as 0).
  for (const std::string opt : {"--huber -1", "--marker-check -3"}) {
    const auto bad = Hovs("stereo-calibrate --dataset " + (dir / "stereo/dataset.json").string() + " " + opt + " -o " +
                          (dir / "badopt").string());
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_NE(bad.output.find(opt.substr(0, opt.find(' ')) + ": '"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(dir / "badopt"));
  }

  // Depth of the first pair's frame (the board and the floor) against its range channel, with the calibrated
  // relative pose.
  const auto d = Hovs("--quiet depth --dataset " + (dir / "stereo/dataset.json").string() + " --stereo " +
                      (dir / "cal/stereo.json").string() + " --width 1024 --height 256 --num-disparities 160 -o " +
                      (dir / "depth").string());
  ASSERT_EQ(d.exit_code, 0) << d.output;
  const auto few = Hovs("depth --dataset " + (dir / "stereo/dataset.json").string() + " --max-points 0 -o " +
                        (dir / "badopt").string());
  EXPECT_EQ(few.exit_code, 2) << few.output;  // (a negative count once wrote a single point)
  EXPECT_NE(few.output.find("--max-points"), std::string::npos) << few.output;
  EXPECT_FALSE(fs::exists(dir / "badopt"));
  const auto dj = nlohmann::json::parse(ReadFile(dir / "depth/depth.json"));
  ASSERT_TRUE(dj.contains("ground_truth"));
  EXPECT_NE(dj["relative_pose_from"].get<std::string>().find("stereo.json"), std::string::npos);
  const auto& band = dj["ground_truth"]["bands"][1];  // 2-4 m: most of the floor
  EXPECT_LT(band["median_relative_error"].get<double>(), 0.03) << band.dump();
  for (const char* f : {"range.exr", "points.ply", "points.vtp", "rectified_left.png", "disparity.png"})
    EXPECT_TRUE(fs::exists(dir / "depth" / f)) << f;

  // A single-unit dataset: one clear error, no output.
  const auto mono = Hovs("--quiet dataset --kind mono_calibration --scene " + Src("scenes/reference_calibration.yaml") +
                         " --count 1 --samples 1 -o " + (dir / "mono").string());
  ASSERT_EQ(mono.exit_code, 0) << mono.output;
  for (const std::string cmd : {"stereo-calibrate", "depth"}) {
    const auto bad = Hovs(cmd + " --dataset " + (dir / "mono/dataset.json").string() + " -o " + (dir / "bad").string());
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_NE(bad.output.find("two units"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  }
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace hovs
