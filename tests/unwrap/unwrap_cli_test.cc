// hovs unwrap from the command line: a rendered frame unwrapped from the scene's exact model, the mapping file
// saved and reused (identical output, faster), the polynomial model from calib_results.txt, the truth
// comparison, and bad input (corrupt mapping, wrong image size, bad layout): one error, exit 2, no output.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "calib/ocam_io.h"
#include "core/io.h"
#include "core/model_fit.h"
#include "tests/cli_helper.h"
#include "tests/core/test_rigs.h"

namespace hovs {
namespace {

namespace fs = std::filesystem;
using test::Hovs;

std::string Src(const std::string& rel) { return std::string(HOVS_SOURCE_DIR) + "/" + rel; }

TEST(UnwrapCli, ViewsFromAModelOrAMappingFileAreIdenticalAndBadInputIsRejected) {
  const fs::path dir = test::Scratch("unwrap-cli", "run");
  const auto render = Hovs("--quiet render --scene " + Src("scenes/reference_board.yaml") + " --samples 1 -o " +
                           (dir / "frame").string());
  ASSERT_EQ(render.exit_code, 0) << render.output;
  const std::string frame = (dir / "frame/dataset.json").string();

  // A small layout: two perspective views and a panorama.
  std::ofstream(dir / "layout.yaml")
      << "views:\n"
         "  - {name: a, yaw: 12, pitch: -33, hfov: 40, width: 320, height: 240}\n"
         "  - {name: b, yaw: 200, pitch: -20, hfov: 60, width: 320, height: 200}\n"
         "  - {name: p, type: cylindrical, width: 1440, height: 240, elevation_min: -60, elevation_max: -5}\n";
  const auto built =
      Hovs("unwrap --model " + Src("scenes/reference_board.yaml") + " --layout " + (dir / "layout.yaml").string() +
           " --input " + frame + " --save-map " + (dir / "map.hmap").string() + " --truth-scene " +
           Src("scenes/reference_board.yaml") + " --truth-samples 1 -o " + (dir / "a").string());
  ASSERT_EQ(built.exit_code, 0) << built.output;
  const auto loaded =
      Hovs("--quiet unwrap --map " + (dir / "map.hmap").string() + " --input " + frame + " -o " + (dir / "b").string());
  ASSERT_EQ(loaded.exit_code, 0) << loaded.output;
  for (const char* v : {"a", "b", "p"}) {
    const std::string rel = std::string("frame0/") + v + ".png";
    ASSERT_TRUE(fs::exists(dir / "a" / rel)) << rel;
    EXPECT_EQ(ReadFile(dir / "a" / rel), ReadFile(dir / "b" / rel)) << rel;
  }
  const auto j = nlohmann::json::parse(ReadFile(dir / "a/views.json"));
  ASSERT_EQ(j["views"].size(), 3u);
  EXPECT_EQ(j["views"][0]["K"].size(), 3u);
  EXPECT_EQ(j["mapping"]["model"]["kind"], "exact");
  // The truth comparison covers the perspective views (1 sample per pixel here: aliased edges on both sides keep
  // PSNR near 22 dB: this is a gross check of alignment; tests/unwrap/geometry_test.cc holds the 35 dB bar).
  EXPECT_GE(j["truth"]["per_frame"]["frame0"]["a"]["psnr_db"].get<double>(), 18.0) << j["truth"].dump();
  EXPECT_FALSE(j["truth"]["per_frame"]["frame0"].contains("p"));

  // Polynomial model from OCamCalib's file.
  const auto rig = test::AlignedRig();
  WriteFileAtomic(dir / "calib_results.txt", calib::FormatOcamCalibResults(PolynomialFromCatadioptric(rig, 5)));
  const auto poly = Hovs("--quiet unwrap --model " + (dir / "calib_results.txt").string() +
                         " --layout panorama --input " + frame + " -o " + (dir / "c").string());
  ASSERT_EQ(poly.exit_code, 0) << poly.output;
  EXPECT_TRUE(fs::exists(dir / "c/frame0/panorama.png"));

  // Bad input: one error line naming the input, exit 2, no output folder.
  std::string bytes = ReadFile(dir / "map.hmap");
  bytes[bytes.size() / 3] ^= 1;
  WriteFileAtomic(dir / "corrupt.hmap", bytes);
  const auto corrupt =
      Hovs("unwrap --map " + (dir / "corrupt.hmap").string() + " --input " + frame + " -o " + (dir / "x").string());
  EXPECT_EQ(corrupt.exit_code, 2) << corrupt.output;
  EXPECT_NE(corrupt.output.find("corrupt.hmap"), std::string::npos) << corrupt.output;
  EXPECT_NE(corrupt.output.find("checksum"), std::string::npos) << corrupt.output;
  EXPECT_FALSE(fs::exists(dir / "x"));

  const auto small = Hovs("--quiet render --scene " + Src("scenes/reference_board.yaml") + " --samples 1 -o " +
                          (dir / "small").string());
  ASSERT_EQ(small.exit_code, 0);
  std::ofstream(dir / "tiny.pgm") << "P2\n4 3\n255\n0 1 2 3\n4 5 6 7\n8 9 10 11\n";
  const auto wrong = Hovs("unwrap --map " + (dir / "map.hmap").string() + " --input " + (dir / "tiny.pgm").string() +
                          " -o " + (dir / "y").string());
  EXPECT_EQ(wrong.exit_code, 2) << wrong.output;
  EXPECT_NE(wrong.output.find("2750 x 2200"), std::string::npos) << wrong.output;
  EXPECT_FALSE(fs::exists(dir / "y"));

  // A failed run saves no mapping file either; --save-map with --map is refused; a render folder is not a
  // folder of images (its manifest is named).
  const auto wrong_saved = Hovs("unwrap --model " + Src("scenes/reference_board.yaml") + " --layout " +
                                (dir / "layout.yaml").string() + " --input " + (dir / "tiny.pgm").string() +
                                " --save-map " + (dir / "wrong.hmap").string() + " -o " + (dir / "y").string());
  EXPECT_EQ(wrong_saved.exit_code, 2) << wrong_saved.output;
  EXPECT_FALSE(fs::exists(dir / "wrong.hmap"));
  EXPECT_FALSE(fs::exists(dir / "y"));
  const auto resave = Hovs("unwrap --map " + (dir / "map.hmap").string() + " --save-map " +
                           (dir / "copy.hmap").string() + " --input " + frame + " -o " + (dir / "y").string());
  EXPECT_EQ(resave.exit_code, 2) << resave.output;
  EXPECT_NE(resave.output.find("--save-map"), std::string::npos) << resave.output;
  EXPECT_FALSE(fs::exists(dir / "copy.hmap"));
  const auto folder = Hovs("unwrap --map " + (dir / "map.hmap").string() + " --input " + (dir / "frame").string() +
                           " -o " + (dir / "y").string());
  EXPECT_EQ(folder.exit_code, 2) << folder.output;
  EXPECT_NE(folder.output.find("dataset.json"), std::string::npos) << folder.output;
  EXPECT_FALSE(fs::exists(dir / "y"));

  // A manifest as --model without units: named, exit 2 (an uncaught JSON exception once, exit 3).
  std::ofstream(dir / "empty.json") << "{\"format\": \"hovs-dataset\"}";
  const auto no_units = Hovs("unwrap --model " + (dir / "empty.json").string() + " --layout panorama --input " + frame +
                             " -o " + (dir / "y").string());
  EXPECT_EQ(no_units.exit_code, 2) << no_units.output;
  EXPECT_NE(no_units.output.find("empty.json"), std::string::npos) << no_units.output;
  EXPECT_FALSE(fs::exists(dir / "y"));

  std::ofstream(dir / "wide.yaml") << "views:\n  - {name: w, hfov: 180}\n";
  const auto wide = Hovs("unwrap --model " + Src("scenes/reference_board.yaml") + " --layout " +
                         (dir / "wide.yaml").string() + " --input " + frame + " -o " + (dir / "z").string());
  EXPECT_EQ(wide.exit_code, 2) << wide.output;
  EXPECT_NE(wide.output.find("wide.yaml"), std::string::npos) << wide.output;
  EXPECT_NE(wide.output.find("180"), std::string::npos) << wide.output;
  EXPECT_FALSE(fs::exists(dir / "z"));
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace hovs
