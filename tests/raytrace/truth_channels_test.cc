// The ground-truth channels a dataset stores (render.truth_channels, --truth) and their compression
// (--truth-compression): a selection holds exactly its channels, with the values the full file holds; every
// compression is lossless; "none" writes no EXR but keeps the sidecar and a valid manifest; bad choices are
// refused by name before anything is written.
#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io.h"
#include "core/manifest.h"
#include "io/image_io.h"
#include "raytrace/render.h"
#include "scenes/dataset.h"
#include "tests/cli_helper.h"
#include "tests/raytrace/small_scene.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;
using raytrace::TruthFileOptions;

TEST(TruthChannels, ParsesPresetsAndListsAndRefusesUnknownWords) {
  EXPECT_EQ(TruthFileOptions::ParseGroups("default", "--truth"), TruthFileOptions{}.groups);
  EXPECT_EQ(TruthFileOptions::ParseGroups("all", "--truth"), TruthFileOptions::AllGroups());
  EXPECT_TRUE(TruthFileOptions::ParseGroups("none", "--truth").empty());
  // Any order in, the file's order out.
  EXPECT_EQ(TruthFileOptions::ParseGroups("mask,M,Z", "--truth"), (std::vector<std::string>{"Z", "mask", "M"}));
  TruthFileOptions t;
  t.groups = {"Z", "N", "mask"};
  EXPECT_EQ(t.Channels(), (std::vector<int>{0, 4, 5, 6, 8}));
  EXPECT_EQ(t.GroupsText(), "Z,N,mask");
  t.groups.clear();
  EXPECT_EQ(t.GroupsText(), "none");
  for (const char* bad : {"", "Q", "Z,Z", "Z,", ",Z", "z", "P.X", "all,Z"}) {
    try {
      TruthFileOptions::ParseGroups(bad, "--truth");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("--truth"), std::string::npos) << e.what(); }
  }
  t.compression = "lzw";
  EXPECT_THROW(t.Check("render"), Error);
}

// Two frames of the quarter-resolution calibration scene with the given channels and compression.
nlohmann::json Render(const std::string& name, const std::vector<std::string>& groups, const std::string& compression,
                      fs::path* out) {
  auto cfg = test::SmallCalibrationScene();
  cfg.render.truth_file.groups = groups;
  cfg.render.truth_file.compression = compression;
  scenes::DatasetOptions o;
  o.count = 2;
  *out = test::Scratch("truth-channels", name);
  scenes::WriteCalibrationDataset(cfg, o, *out, {{"hovs", "test"}});
  return LoadDatasetManifest(*out / "dataset.json");
}

TEST(TruthChannels, ASelectionHoldsExactlyItsChannelsWithTheFullFilesValues) {
  fs::path all_dir, dir;
  const auto all = Render("all", TruthFileOptions::AllGroups(), "piz", &all_dir);
  const std::vector<std::string> picked = {"Z", "N.X", "N.Y", "N.Z", "id", "mask"};
  for (const std::string compression : {"piz", "zip", "rle"}) {
    const auto m = Render("default-" + compression, TruthFileOptions{}.groups, compression, &dir);
    EXPECT_EQ(m["generator"]["truth_channels"], "Z,N,id,mask");
    EXPECT_EQ(m["generator"]["truth_compression"], compression);
    for (size_t f = 0; f < 2; ++f) {
      const auto& v = m["frames"][f]["views"][0]["ground_truth"];
      const auto full = io::ReadExr(all_dir / all["frames"][f]["views"][0]["ground_truth"]["exr"].get<std::string>());
      const auto part = io::ReadExr(dir / v["exr"].get<std::string>());
      ASSERT_EQ(part.channels.size(), picked.size());
      for (const auto& name : picked) {
        const auto &a = full.at(name), &b = part.at(name);
        ASSERT_EQ(a.size(), b.size());
        // Bit for bit (the sky's +inf range included): selection and compression lose nothing.
        EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << name << " " << compression;
      }
      const auto side = nlohmann::json::parse(ReadFile(dir / v["sidecar"].get<std::string>()));
      ASSERT_EQ(side["exr_channels"].size(), picked.size());
      for (size_t c = 0; c < picked.size(); ++c) EXPECT_EQ(side["exr_channels"][c]["name"], picked[c]);
    }
    if (compression == "piz")
      EXPECT_LT(fs::file_size(dir / m["frames"][0]["views"][0]["ground_truth"]["exr"].get<std::string>()),
                fs::file_size(all_dir / all["frames"][0]["views"][0]["ground_truth"]["exr"].get<std::string>()) / 2);
  }
}

TEST(TruthChannels, NoneWritesNoImageButKeepsTheSidecarAndAValidManifest) {
  fs::path dir;
  const auto m = Render("none", {}, "piz", &dir);
  for (const auto& fr : m["frames"]) {
    const auto& gt = fr["views"][0]["ground_truth"];
    EXPECT_FALSE(gt.contains("exr"));
    const auto side = nlohmann::json::parse(ReadFile(dir / gt["sidecar"].get<std::string>()));
    EXPECT_EQ(side["boards"][0]["visible_corners"], 35);
    EXPECT_TRUE(side["exr_channels"].empty());
  }
  EXPECT_FALSE(fs::exists(dir / "truth" / "unit0_0000.exr"));
  // The consumers that need per-pixel truth say so by name.
  const auto r = test::Hovs("export --dataset " + (dir / "dataset.json").string() + " --out " +
                            (dir.parent_path() / "export").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no ground-truth image"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.parent_path() / "export"));
}

TEST(TruthChannels, BadChoicesOnTheCommandLineAreRefusedBeforeAnythingIsWritten) {
  const fs::path dir = test::Scratch("truth-channels", "cli");
  const std::string scene = std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml";
  for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {"--truth Z,Q", "--truth: unknown ground-truth channel 'Q'"},
           {"--truth Z,Z", "listed twice"},
           {"--truth-compression lzw", "unknown OpenEXR compression 'lzw'"}}) {
    const auto r =
        test::Hovs("dataset --scene " + scene + " --downscale 10 -n 1 " + args + " --out " + (dir / "out").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  // In the scene file: the key's place in the file.
  std::string bad = ReadFile(scene);
  const size_t at = bad.find("ground_truth: true");
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, 18, "ground_truth: true, truth_channels: Z+N");
  WriteFileAtomic(dir / "bad.yaml", bad);
  const auto r = test::Hovs("dataset --scene " + (dir / "bad.yaml").string() + " -n 1 --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("render.truth_channels"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace hovs
