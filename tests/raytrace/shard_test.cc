// Sharded datasets: N shards merged are the set one process writes (images, ground truth, manifest apart from
// the render timings), and shards that do not belong together are refused by name. A dataset killed mid-run
// resumes (--resume) to the set an uninterrupted run writes.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <sstream>
#include <thread>

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
  refused({dir / "s2_0", dir / "s3_1"}, "is shard 1 of 3, the first of 2");
  refused({dir / "whole"}, "is not a shard");
  // Every file is verified against its shard's checksum: a tampered image, a tampered checksum, a frame without
  // checksums, a malformed shard record (these merged with exit 0, or ended in a JSON exception).
  const fs::path shard = dir / "s2_1", manifest = shard / "dataset.json";
  const std::string good = ReadFile(manifest);
  const auto m = nlohmann::json::parse(good);
  const fs::path image = shard / m["frames"][0]["views"][0]["image"].get<std::string>();
  const std::string pixels = ReadFile(image);
  std::string flipped = pixels;
  flipped[flipped.size() / 2] ^= 0x10;
  WriteFileAtomic(image, flipped);
  refused({dir / "s2_0", shard}, "does not match its checksum");
  WriteFileAtomic(image, pixels);
  const auto edited = [&](const std::function<void(nlohmann::json*)>& edit) {
    nlohmann::json e = m;
    edit(&e);
    WriteFileAtomic(manifest, e.dump(2));
  };
  edited([&](nlohmann::json* e) {
    (*e)["frames"][0]["checksums"][m["frames"][0]["views"][0]["image"].get<std::string>()] = "fnv1a64:0000000000000000";
  });
  refused({dir / "s2_0", shard}, "does not match its checksum");
  edited([](nlohmann::json* e) { (*e)["frames"][0].erase("checksums"); });
  refused({dir / "s2_0", shard}, "has no checksums");
  edited([](nlohmann::json* e) { (*e)["shard"]["count"] = 2000000000; });
  refused({dir / "s2_0", shard}, "shard.count");
  edited([](nlohmann::json* e) { (*e)["shard"]["index"] = "1"; });
  refused({dir / "s2_0", shard}, "shard.index");
  WriteFileAtomic(manifest, good);
  // A shard's thumbnail carries no checksum: a changed one never reaches the merged set, whose page makes its own
  // from the verified images (the bytes one process writes).
  const fs::path thumb = shard / "thumbs" / image.filename();
  ASSERT_TRUE(fs::is_regular_file(thumb));
  WriteFileAtomic(thumb, ReadFile(thumb) + "tampered");
  EXPECT_NO_THROW(scenes::MergeDatasetShards({dir / "s2_0", shard}, dir / "good"));
  EXPECT_EQ(ReadFile(dir / "good" / "thumbs" / image.filename()),
            ReadFile(dir / "whole" / "thumbs" / image.filename()));
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

// The staging folder a run writing dir/name is using (.name.partial-<pid>-...), or empty.
fs::path StagingOf(const fs::path& dir, const std::string& name) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind("." + name + ".partial-", 0) == 0) return e.path();
  return {};
}

size_t Lines(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return 0;
  std::istringstream in(ReadFile(p));
  std::string line;
  size_t n = 0;
  while (std::getline(in, line)) n += !line.empty();
  return n;
}

TEST(DatasetResume, AKilledRunResumesToTheSetAnUninterruptedRunWrites) {
  const fs::path dir = test::Scratch("dataset", "resume");
  const std::string args = "-q dataset --scene " + std::string(HOVS_SOURCE_DIR) +
                           "/scenes/reference_calibration.yaml -n 6 --seed 4 --downscale 5 --samples 64 --out ";
  ASSERT_EQ(test::Hovs(args + (dir / "whole").string()).exit_code, 0);
  // A run killed (SIGKILL: nothing of hovs runs) once its journal lists two whole frames.
  std::vector<std::string> argv = {HOVS_BINARY};
  std::istringstream words(args + (dir / "resumed").string());
  for (std::string w; words >> w;) argv.push_back(w);
  std::vector<char*> cargv;
  for (auto& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, HOVS_BINARY, nullptr, nullptr, cargv.data(), environ), 0);
  fs::path staging;
  for (int k = 0; k < 3000; ++k) {  // up to 60 s
    staging = StagingOf(dir, "resumed");
    if (!staging.empty() && Lines(staging / "frames.jsonl") >= 3) break;  // the header and two frames
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_FALSE(staging.empty());
  ASSERT_GE(Lines(staging / "frames.jsonl"), 3u) << "the run ended before two frames were written";
  ASSERT_FALSE(fs::exists(dir / "resumed"));
  // What a kill mid-frame leaves: a half-written image; and a kept frame's file damaged since (redone).
  WriteFileAtomic(staging / "images" / "half-written.png", "\x89PNG truncated");
  const std::string journal = ReadFile(staging / "frames.jsonl");
  const size_t second_line = journal.find('\n') + 1;
  const auto first = nlohmann::json::parse(journal.substr(second_line, journal.find('\n', second_line) - second_line));
  const size_t third_line = journal.find('\n', second_line) + 1;
  const auto second = nlohmann::json::parse(journal.substr(third_line, journal.find('\n', third_line) - third_line));
  const fs::path damaged = staging / first["views"][0]["image"].get<std::string>();
  fs::resize_file(damaged, fs::file_size(damaged) / 2);
  // A --resume with a mistyped option is refused and removes nothing: the kept frames stay for the right command
  // (the kept folder is moved aside before the configuration check; a refused run must not delete it).
  const std::string kept_journal = ReadFile(staging / "frames.jsonl");
  const auto wrong = test::Hovs(args + (dir / "resumed").string() + " --resume --elevation -30 20");
  EXPECT_EQ(wrong.exit_code, 2) << wrong.output;
  EXPECT_NE(wrong.output.find("another configuration"), std::string::npos) << wrong.output;
  staging = StagingOf(dir, "resumed");
  ASSERT_FALSE(staging.empty()) << "the refused --resume deleted the kept run";
  EXPECT_EQ(ReadFile(staging / "frames.jsonl"), kept_journal);
  EXPECT_TRUE(fs::exists(staging / first["views"][0]["image"].get<std::string>()));
  // The same command with --resume continues.
  const auto r = test::Hovs(args + (dir / "resumed").string() + " --resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(StagingOf(dir, "resumed").empty());
  const auto a = nlohmann::json::parse(ReadFile(dir / "whole" / "dataset.json"));
  const auto b = nlohmann::json::parse(ReadFile(dir / "resumed" / "dataset.json"));
  EXPECT_EQ(WithoutTimings(a), WithoutTimings(b));
  size_t files = 0;
  for (const auto& fr : a["frames"])
    for (const auto& v : fr["views"])
      for (const std::string& f : {v["image"].get<std::string>(), v["ground_truth"]["exr"].get<std::string>(),
                                   v["ground_truth"]["sidecar"].get<std::string>()}) {
        EXPECT_EQ(ReadFile(dir / "whole" / f), ReadFile(dir / "resumed" / f)) << f;
        ++files;
      }
  EXPECT_EQ(files, 18u);
  // The second frame was kept from the killed run (its render time is that run's), the damaged first redone.
  EXPECT_EQ(b["frames"][second["id"].get<size_t>()]["render_seconds"], second["render_seconds"]);
  EXPECT_NE(b["frames"][first["id"].get<size_t>()]["render_seconds"], first["render_seconds"]);
  EXPECT_FALSE(fs::exists(dir / "resumed" / "images" / "half-written.png"));
  EXPECT_FALSE(fs::exists(dir / "resumed" / "frames.jsonl"));
  for (const auto& fr : b["frames"]) EXPECT_EQ(fr["checksums"].size(), 3u);
}

}  // namespace
}  // namespace hovs
