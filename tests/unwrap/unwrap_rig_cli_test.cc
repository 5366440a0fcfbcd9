// hovs unwrap over a rig: a rendered two-unit dataset expanded into the binocular preset's 3 + 3 views and into a
// mixed layout, each view identical to the same view unwrapped from its own unit alone; the rig mapping file
// reused; frames that lack a unit's image listed and not expanded; pairs and rigs that do not fit refused.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/io.h"
#include "io/image_io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {

namespace fs = std::filesystem;
using test::Hovs;

std::string Src(const std::string& rel) { return std::string(HOVS_SOURCE_DIR) + "/" + rel; }

TEST(UnwrapRigCli, TwoUnitsExpandTogetherAsEachAloneAndUnpairedFramesAreCounted) {
  const fs::path dir = test::Scratch("unwrap-rig-cli", "run");
  const auto set = Hovs("--quiet dataset --kind stereo_aruco --scene " + Src("scenes/reference_stereo.yaml") +
                        " --count 2 --samples 1 --seed 2 --downscale 5 --truth none -o " + (dir / "set").string());
  ASSERT_EQ(set.exit_code, 0) << set.output;
  const std::string manifest = (dir / "set/dataset.json").string();

  const auto bino = Hovs("--quiet unwrap --model " + manifest + " --layout binocular --input " + manifest +
                         " --save-map " + (dir / "rig.hmap").string() + " -o " + (dir / "bino").string());
  ASSERT_EQ(bino.exit_code, 0) << bino.output;
  const auto j = nlohmann::json::parse(ReadFile(dir / "bino/views.json"));
  EXPECT_EQ(j["units"], nlohmann::json({"left", "right"}));
  EXPECT_EQ(j["frames_expanded"], 2);
  EXPECT_EQ(j["frames_unpaired"], 0);
  ASSERT_EQ(j["views"].size(), 6u);
  EXPECT_EQ(j["views"][0]["unit"], "left");
  EXPECT_EQ(j["views"][5]["unit"], "right");

  // The right unit's front view, unwrapped from the right unit alone with the same view: identical bytes.
  std::ofstream(dir / "one.yaml") << "views:\n  - {name: unit1_view0, yaw: 0, pitch: -30, hfov: 65, width: 1200, "
                                     "height: 700}\n";
  const auto alone = Hovs("--quiet unwrap --model " + manifest + " --unit right --fixed-elevation --layout " +
                          (dir / "one.yaml").string() + " --input " + manifest + " -o " + (dir / "alone").string());
  ASSERT_EQ(alone.exit_code, 0) << alone.output;
  const auto fixed = Hovs("--quiet unwrap --model " + manifest + " --layout binocular --fixed-elevation --input " +
                          manifest + " -o " + (dir / "fixed").string());
  ASSERT_EQ(fixed.exit_code, 0) << fixed.output;
  EXPECT_EQ(ReadFile(dir / "alone/frame1/unit1_view0.png"), ReadFile(dir / "fixed/frame1/unit1_view0.png"));

  // The saved rig mapping gives the same views.
  const auto reuse = Hovs("--quiet unwrap --map " + (dir / "rig.hmap").string() + " --input " + manifest + " -o " +
                          (dir / "reuse").string());
  ASSERT_EQ(reuse.exit_code, 0) << reuse.output;
  for (const char* v : {"unit0_view180", "unit1_view60"})
    EXPECT_EQ(ReadFile(dir / "bino/frame0" / (std::string(v) + ".png")),
              ReadFile(dir / "reuse/frame0" / (std::string(v) + ".png")))
        << v;

  // A frame whose right image is missing: listed, not expanded alone.
  auto m = nlohmann::json::parse(ReadFile(manifest));
  auto& views = m["frames"][1]["views"];
  views.erase(views.begin() + 1);
  WriteFileAtomic(dir / "set/missing.json", m.dump(1));
  const auto half = Hovs("--quiet unwrap --map " + (dir / "rig.hmap").string() + " --input " +
                         (dir / "set/missing.json").string() + " -o " + (dir / "half").string());
  ASSERT_EQ(half.exit_code, 0) << half.output;
  const auto h = nlohmann::json::parse(ReadFile(dir / "half/views.json"));
  EXPECT_EQ(h["frames_expanded"], 1);
  ASSERT_EQ(h["unpaired"].size(), 1u);
  EXPECT_EQ(h["unpaired"][0]["frame"], "frame1");
  EXPECT_EQ(h["unpaired"][0]["missing_units"], nlohmann::json({"right"}));
  EXPECT_FALSE(fs::exists(dir / "half/frame1"));

  // A folder of unit subfolders, and a mixed layout (one view of each unit, one panorama).
  fs::create_directories(dir / "pairs/left");
  fs::create_directories(dir / "pairs/right");
  fs::copy_file(dir / "set/images/left_0000.png", dir / "pairs/left/a.png");
  fs::copy_file(dir / "set/images/right_0000.png", dir / "pairs/right/a.png");
  std::ofstream(dir / "mixed.yaml") << "views:\n  - {name: back, unit: left, yaw: 180, width: 300, height: 200}\n"
                                       "  - {name: pano, unit: right, type: cylindrical, width: 720, height: 120, "
                                       "elevation_min: -60, elevation_max: -5}\n"
                                       "  - {name: rig, unit: all, type: cylindrical, width: 720, height: 80, "
                                       "elevation_min: -45, elevation_max: -8}\n";
  const auto mixed = Hovs("--quiet unwrap --model " + manifest + " --layout " + (dir / "mixed.yaml").string() +
                          " --input " + (dir / "pairs").string() + " -o " + (dir / "mixed").string());
  ASSERT_EQ(mixed.exit_code, 0) << mixed.output;
  EXPECT_TRUE(fs::exists(dir / "mixed/a/back.png"));
  EXPECT_TRUE(fs::exists(dir / "mixed/a/pano.png"));
  EXPECT_TRUE(fs::exists(dir / "mixed/a/rig.png"));  // both units blended, their poses from the manifest
  EXPECT_EQ(nlohmann::json::parse(ReadFile(dir / "mixed/views.json"))["views"][2]["unit"], "all");

  // Bad input: one error naming it, exit 2, no output.
  const auto expect_error = [&](const std::string& args, const std::string& needle) {
    const auto r = Hovs("unwrap " + args + " -o " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad")) << args;
  };
  int w = 0, hh = 0, c = 0;
  const auto px = io::ReadImage(dir / "pairs/right/a.png", &w, &hh, &c);
  fs::create_directories(dir / "sizes/left");
  fs::create_directories(dir / "sizes/right");
  fs::copy_file(dir / "pairs/left/a.png", dir / "sizes/left/a.png");
  io::WriteImage(dir / "sizes/right/a.png", w / 2, hh / 2, c,
                 std::vector<float>(px.begin(), px.begin() + (w / 2) * (hh / 2) * c), 8);
  expect_error("--map " + (dir / "rig.hmap").string() + " --input " + (dir / "sizes").string(), "sizes/right/a.png");
  fs::create_directories(dir / "oneunit/left");
  fs::copy_file(dir / "pairs/left/a.png", dir / "oneunit/left/a.png");
  expect_error("--map " + (dir / "rig.hmap").string() + " --input " + (dir / "oneunit").string(),
               "no subfolder 'right'");
  std::ofstream(dir / "middle.yaml") << "views:\n  - {name: m, unit: middle, yaw: 0}\n";
  expect_error("--model " + manifest + " --layout " + (dir / "middle.yaml").string() + " --input " + manifest,
               "left (0), right (1)");
  expect_error("--model " + Src("scenes/reference_board.yaml") + " --layout binocular --input " + manifest,
               "several units");
}

}  // namespace
}  // namespace hovs
