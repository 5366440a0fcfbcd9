// Sharded datasets: N shards merged are the set one process writes (images, ground truth, manifest apart from
// the render timings), and shards that do not belong together are refused by name.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io.h"
#include "scenes/dataset.h"
#include "tests/cli_helper.h"
#include "tests/raytrace/small_scene.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

nlohmann::json WithoutTimings(nlohmann::json m) {
  for (auto& fr : m["frames"]) fr.erase("render_seconds");
  return m;
}

TEST(DatasetShards, MergedShardsAreTheSetOneProcessWrites) {
  const fs::path dir = test::Scratch("dataset", "shards");
  const auto cfg = test::SmallCalibrationScene();
  scenes::DatasetOptions o;
  o.count = 5;
  o.seed = 7;
  scenes::WriteCalibrationDataset(cfg, o, dir / "whole", {{"hovs", "test"}});
  for (int n : {2, 3}) {
    std::vector<fs::path> shards;
    for (int i = 0; i < n; ++i) {
      scenes::DatasetOptions s = o;
      s.shard_index = i, s.shard_count = n;
      shards.push_back(dir / ("s" + std::to_string(n) + "_" + std::to_string(i)));
      scenes::WriteCalibrationDataset(cfg, s, shards.back(), {{"hovs", "test"}});
    }
    std::reverse(shards.begin(), shards.end());  // any order
    const fs::path merged = dir / ("merged" + std::to_string(n));
    scenes::MergeDatasetShards(shards, merged);
    const auto a = nlohmann::json::parse(ReadFile(dir / "whole" / "dataset.json"));
    const auto b = nlohmann::json::parse(ReadFile(merged / "dataset.json"));
    EXPECT_EQ(WithoutTimings(a), WithoutTimings(b)) << n << " shards";
    int files = 0;
    for (const auto& fr : a["frames"])
      for (const auto& v : fr["views"])
        for (const std::string& f : {v["image"].get<std::string>(), v["ground_truth"]["exr"].get<std::string>(),
                                     v["ground_truth"]["sidecar"].get<std::string>()}) {
          EXPECT_EQ(ReadFile(dir / "whole" / f), ReadFile(merged / f)) << f << " differs (" << n << " shards)";
          ++files;
        }
    EXPECT_EQ(files, 15);
  }
  // Shards that do not belong together, named.
  scenes::DatasetOptions other = o;
  other.seed = 8, other.shard_index = 1, other.shard_count = 2;
  scenes::WriteCalibrationDataset(cfg, other, dir / "other_seed", {{"hovs", "test"}});
  const auto refused = [&](const std::vector<fs::path>& shards, const std::string& needle) {
    try {
      scenes::MergeDatasetShards(shards, dir / "bad");
      ADD_FAILURE() << "merged";
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what(); }
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  refused({dir / "s2_0", dir / "other_seed"}, "other_seed/dataset.json: does not belong with");
  refused({dir / "s2_0"}, "shard 1 of 2 is missing");
  refused({dir / "s2_0", dir / "s2_0"}, "given twice");
  refused({dir / "s2_0", dir / "s3_1"}, "is a shard of 3 but the first is of 2");
  refused({dir / "whole"}, "is not a shard");
  // From the command line: a bad shard is one clear error, exit 2, nothing written.
  const auto bad = test::Hovs("-q dataset --scene " + std::string(HOVS_SOURCE_DIR) +
                              "/scenes/reference_calibration.yaml -n 2 --shard 2/2 -o " + (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("needs 0 <= I < N"), std::string::npos) << bad.output;
  const auto merge = test::Hovs("-q merge " + (dir / "s2_0").string() + " --out " + (dir / "bad").string());
  EXPECT_EQ(merge.exit_code, 2) << merge.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

TEST(DatasetShards, ADepthSequenceShardsAndMergesToo) {
  const fs::path dir = test::Scratch("dataset", "depth-shards");
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/street.yaml");
  scenes::DownscaleCameras(&cfg, 10);
  cfg.render.samples = 1;
  scenes::DatasetOptions o = scenes::DatasetOptions::ForKind("depth_sequence");
  o.count = 3;
  scenes::WriteDepthSequence(cfg, o, dir / "whole", {{"hovs", "test"}});
  std::vector<fs::path> shards;
  for (int i = 0; i < 2; ++i) {
    scenes::DatasetOptions s = o;
    s.shard_index = i, s.shard_count = 2;
    shards.push_back(dir / ("s" + std::to_string(i)));
    scenes::WriteDepthSequence(cfg, s, shards.back(), {{"hovs", "test"}});
  }
  scenes::MergeDatasetShards(shards, dir / "merged");
  const auto a = nlohmann::json::parse(ReadFile(dir / "whole" / "dataset.json"));
  EXPECT_EQ(WithoutTimings(a), WithoutTimings(nlohmann::json::parse(ReadFile(dir / "merged" / "dataset.json"))));
  for (const auto& fr : a["frames"])
    for (const auto& v : fr["views"])
      EXPECT_EQ(ReadFile(dir / "whole" / v["image"].get<std::string>()),
                ReadFile(dir / "merged" / v["image"].get<std::string>()));
  EXPECT_TRUE(fs::exists(dir / "merged" / "index.html"));
}

}  // namespace
}  // namespace hovs
