// `hovs design` end to end: the report folder and its figures, and bad input through the command line (one
// clear error, non-zero exit, no report written, an earlier report left intact). Needs an X display: CTest
// runs it under xvfb-run.
#include <gtest/gtest.h>

#include <functional>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/io.h"
#include "tests/cli_helper.h"
#include "results/plot.h"

namespace {
namespace fs = std::filesystem;

using hovs::test::CliRun;
using hovs::test::Hovs;
fs::path Scratch(const std::string& name) { return hovs::test::Scratch("design-cli", name); }

const std::string kReference = std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml";

TEST(DesignCli, WritesTheCompleteReport) {
  const fs::path out = Scratch("report");
  const CliRun r = Hovs("design --config " + kReference + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("integer-mm optimum   a = 48.0000 mm, b = 44.0000 mm"), std::string::npos) << r.output;
  for (const char* f :
       {"config.yaml", "sweep.csv", "design.json", "radial_resolution.csv", "index.html", "summary.txt"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  const auto j = nlohmann::json::parse(hovs::ReadFile(out / "design.json"));
  EXPECT_NEAR(j["integer_mm_optimum"]["a"].get<double>(), 0.048, 1e-12);
  EXPECT_NEAR(j["integer_mm_optimum"]["b"].get<double>(), 0.044, 1e-12);
  EXPECT_TRUE(j["continuous_optimum"]["feasible"].get<bool>());
  EXPECT_TRUE(j["versions"].contains("vtk"));
  EXPECT_TRUE(j["versions"].contains("nlopt"));
  EXPECT_EQ(j["config"]["objective"], "smallest_system");
  // Sweep CSV: header plus one row per design.
  std::ifstream csv(out / "sweep.csv");
  std::string line;
  size_t rows = 0;
  while (std::getline(csv, line)) rows += !line.empty() && line[0] != '#' && line[0] != 'a';
  EXPECT_EQ(rows, j["sweep"]["points"].get<size_t>());
  // Figures are pictures, not blank canvases.
  for (const char* f : {"vertical_field.png", "upper_bound.png", "rim_radius.png", "system_length.png",
                        "feasible_region.png", "radial_resolution.png"}) {
    const auto s = hovs::results::PngStats(out / "figures" / f);
    EXPECT_GE(s.width, 800) << f;
    EXPECT_GT(s.non_white_fraction, 0.02) << f;
    EXPECT_GT(s.stddev, 20) << f;
  }
  const std::string html = hovs::ReadFile(out / "index.html");
  for (const char* f : {"figures/vertical_field.png", "figures/feasible_region.png", "integer-mm optimum"})
    EXPECT_NE(html.find(f), std::string::npos) << f;
  fs::remove_all(out.parent_path());
}

void ExpectRejected(const std::string& yaml, const std::string& needle) {
  const fs::path dir = Scratch("bad");
  fs::create_directories(dir);
  const fs::path cfg = dir / "bad.yaml";
  std::ofstream(cfg) << yaml;
  const fs::path out = dir / "report";
  const CliRun r = Hovs("design --config " + cfg.string() + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out)) << "no report for bad input";
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u) << "nothing but the config is left in the folder";
  fs::remove_all(dir);
}

const std::string kCamera =
    "camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.020}\n";

TEST(DesignCli, BadInputGetsOneClearErrorAndNoReport) {
  ExpectRejected(kCamera + "mirror: {rim_diameter: 0.08}\nshape: round\n", "unknown key 'shape'");
  ExpectRejected(kCamera + "mirror: {rim_diameter: -0.08}\n", "must be positive");
  ExpectRejected(kCamera + "mirror: {rim_diameter: .nan}\n", "finite");
  ExpectRejected(kCamera + "mirror: {rim_diameter: 0.08}\nsearch: {b: [0, 0.08]}\n", "b minimum must be positive");
  ExpectRejected(
      kCamera + "mirror: {rim_diameter: 0.08}\nconstraints: {min_rim_radius_px: 1500}\nsearch: {grid: [21, 21]}\n",
      "no design in the search box satisfies the constraints");
  const CliRun missing = Hovs("design --config /nonexistent.yaml --out /tmp/never");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("/nonexistent.yaml: config file not found"), std::string::npos) << missing.output;
}

TEST(DesignCli, AFailedRunLeavesTheEarlierReportIntact) {
  const fs::path dir = Scratch("keep");
  fs::create_directories(dir);
  const fs::path out = dir / "report";
  ASSERT_EQ(Hovs("-q design --config " + kReference + " --out " + out.string()).exit_code, 0);
  const std::string before = hovs::ReadFile(out / "design.json");
  const fs::path cfg = dir / "empty.yaml";
  std::ofstream(cfg) << kCamera << "mirror: {rim_diameter: 0.08}\nconstraints: {min_rim_radius_px: 1500}\n";
  EXPECT_EQ(Hovs("design --config " + cfg.string() + " --out " + out.string()).exit_code, 2);
  EXPECT_EQ(hovs::ReadFile(out / "design.json"), before);
  fs::remove_all(dir);
}

TEST(DesignCli, SweepShardsMergeToTheReportOneProcessWrites) {
  // The reference config on a 61 x 61 grid, as one process and as 3 shards merged (design.json equal apart from
  // its timings, sweep.csv and the other tables byte for byte); a shard of another grid refused by name.
  const fs::path dir = Scratch("shards");
  fs::create_directories(dir);
  std::string config = hovs::ReadFile(kReference);
  const size_t at = config.find("grid: [201, 201]");
  ASSERT_NE(at, std::string::npos);
  hovs::WriteFileAtomic(dir / "small.yaml", std::string(config).replace(at, 16, "grid: [61, 61]"));
  hovs::WriteFileAtomic(dir / "other.yaml", std::string(config).replace(at, 16, "grid: [61, 60]"));
  const std::string small = (dir / "small.yaml").string();
  ASSERT_EQ(Hovs("-q design --config " + small + " --out " + (dir / "whole").string()).exit_code, 0);
  std::string shards;
  for (int i = 0; i < 3; ++i) {
    const CliRun r = Hovs("-q design --config " + small + " --shard " + std::to_string(i) + "/3 --out " +
                          (dir / std::to_string(i)).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(fs::exists(dir / std::to_string(i) / "index.html"));
    shards += (dir / std::to_string(i)).string() + " ";
  }
  const CliRun m = Hovs("-q merge " + shards + "--out " + (dir / "merged").string());
  ASSERT_EQ(m.exit_code, 0) << m.output;
  // (summary.txt names its own folder.)
  for (const char* f : {"sweep.csv", "radial_resolution.csv", "config.yaml"})
    EXPECT_EQ(hovs::ReadFile(dir / "whole" / f), hovs::ReadFile(dir / "merged" / f)) << f;
  auto a = nlohmann::json::parse(hovs::ReadFile(dir / "whole" / "design.json"));
  auto b = nlohmann::json::parse(hovs::ReadFile(dir / "merged" / "design.json"));
  a.erase("seconds"), b.erase("seconds");
  EXPECT_EQ(a, b);
  ASSERT_EQ(
      Hovs("-q design --config " + (dir / "other.yaml").string() + " --shard 2/3 --out " + (dir / "other").string())
          .exit_code,
      0);
  const CliRun bad = Hovs("merge " + (dir / "0").string() + " " + (dir / "1").string() + " " +
                          (dir / "other").string() + " --out " + (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find((dir / "other" / "design-shard.json").string() + ": does not belong"), std::string::npos)
      << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  // An edited value merges neither with its checksum as written nor with the checksum made again (the shard's
  // first row is evaluated again); malformed records are named errors, a wrapped --shard is refused.
  const fs::path file = dir / "1" / "design-shard.json";
  const std::string good = hovs::ReadFile(file);
  const auto refused = [&](const std::function<void(nlohmann::json*)>& edit, const std::string& needle) {
    nlohmann::json j = nlohmann::json::parse(good);
    edit(&j);
    hovs::WriteFileAtomic(file, j.dump());
    const CliRun r = Hovs("merge " + shards + "--out " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << needle << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  refused([](nlohmann::json* j) { (*j)["rows"]["rim_px"][0] = 1.0; }, "rows_checksum");
  refused(
      [](nlohmann::json* j) {
        (*j)["rows"]["rim_px"][0] = 1.0;
        (*j)["shard"]["rows_checksum"] = hovs::TextChecksum((*j)["rows"].dump());
      },
      "where the design evaluates to");
  refused([](nlohmann::json* j) { (*j)["shard"]["count"] = 2000000000; }, "shard.count");
  refused([](nlohmann::json* j) { (*j)["rows"]["objective"] = "many"; }, "rows");
  refused([](nlohmann::json* j) { (*j)["config"] = 3; }, "config");
  hovs::WriteFileAtomic(file, good);
  const CliRun wrapped =
      Hovs("design --config " + small + " --shard 4294967296/4294967297 --out " + (dir / "wrapped").string());
  EXPECT_EQ(wrapped.exit_code, 2) << wrapped.output;
  EXPECT_NE(wrapped.output.find("--shard"), std::string::npos) << wrapped.output;
  EXPECT_FALSE(fs::exists(dir / "wrapped"));
  const CliRun family = Hovs("design --config " + std::string(HOVS_SOURCE_DIR) + "/design/turret.yaml --shard 0/2 " +
                             "--out " + (dir / "family").string());
  EXPECT_EQ(family.exit_code, 2);
  EXPECT_NE(family.output.find("cannot be sharded"), std::string::npos) << family.output;
}

}  // namespace
