#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <functional>

#include "core/error.h"
#include "core/io.h"
#include "core/manifest.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

fs::path TempRoot() {
  const fs::path p = fs::temp_directory_path() / ("hovs-io-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

TEST(Io, AtomicWriteReplacesContentAndLeavesNoTemporaries) {
  const fs::path root = TempRoot();
  WriteFileAtomic(root / "a.txt", "first");
  WriteFileAtomic(root / "a.txt", "second");
  EXPECT_EQ(ReadFile(root / "a.txt"), "second");
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(root)) ++files;
  EXPECT_EQ(files, 1);
  EXPECT_THROW(ReadFile(root / "missing.txt"), Error);
  fs::remove_all(root);
}

TEST(Io, StagedDirectoryIsAllOrNothing) {
  const fs::path root = TempRoot();
  const fs::path target = root / "report";
  {
    StagedDirectory stage(target);
    WriteFileAtomic(stage.staging() / "x.json", "{}");
    // No commit: an error happened.
  }
  EXPECT_FALSE(fs::exists(target));
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(root)) ++entries;
  EXPECT_EQ(entries, 0) << "the staging folder is removed";
  {
    StagedDirectory stage(target);
    WriteFileAtomic(stage.staging() / "x.json", "{\"v\": 1}");
    stage.Commit();
  }
  EXPECT_EQ(ReadFile(target / "x.json"), "{\"v\": 1}");
  {
    StagedDirectory stage(target);
    WriteFileAtomic(stage.staging() / "y.json", "{}");
    // An aborted second run leaves the first report intact.
  }
  EXPECT_TRUE(fs::exists(target / "x.json"));
  EXPECT_FALSE(fs::exists(target / "y.json"));
  fs::remove_all(root);
}

TEST(Io, StagingLeftByAKilledRunIsRemovedByTheNextOne) {
  // A run killed before its destructor (Ctrl-C, a crash) leaves its hidden staging folder; the next run for the
  // same target removes it when its process is gone, and leaves a live process's folder and other names alone.
  const fs::path root = TempRoot();
  const fs::path dead = root / ".report.partial-999999999-1-0";   // beyond any pid_max: no such process
  const fs::path dead_old = root / ".report.old-999999999-2-0";
  const fs::path live = root / (".report.partial-" + std::to_string(::getpid()) + "-3-0");
  const fs::path other = root / ".other.partial-999999999-4-0";
  for (const auto& p : {dead, dead_old, live, other}) fs::create_directories(p / "images");
  {
    StagedDirectory stage(root / "report");
    EXPECT_FALSE(fs::exists(dead));
    EXPECT_FALSE(fs::exists(dead_old));
    EXPECT_TRUE(fs::exists(live));
    EXPECT_TRUE(fs::exists(other));
    EXPECT_TRUE(fs::exists(stage.staging()));
  }
  fs::remove_all(root);
}

TEST(Manifest, MalformedFieldsAreNamedErrors) {
  // A rendered set's shape (ground truth present) and a capture's (device_ns, no ground truth) are accepted.
  const nlohmann::json ok = nlohmann::json::parse(R"({"format": "hovs-dataset", "units": [{"name": "left"}, {"name": "right"}],
    "frames": [{"views": [{"unit": "left", "image": "images/l.png", "ground_truth": {"exr": "t/l.exr", "sidecar": "t/l.json"}},
                          {"unit": "right", "image": "images/r.png", "device_ns": 123456789}]}]})");
  EXPECT_NO_THROW(CheckDatasetManifest(ok, "m.json"));
  const auto rejected = [&](const std::function<void(nlohmann::json*)>& spoil, const std::string& needle) {
    nlohmann::json m = ok;
    spoil(&m);
    try {
      CheckDatasetManifest(m, "m.json");
      ADD_FAILURE() << "accepted: " << m.dump();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("m.json"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // Each of these once reached a command as a JSON exception ("internal error", exit 3).
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][0]["image"] = 5; }, "frames[0].views[0]");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][1].erase("unit"); }, "frames[0].views[1]");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][1]["unit"] = "middle"; }, "'middle' is not among");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][0]["ground_truth"] = {{"exr", 3}}; }, "ground_truth");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][1]["device_ns"] = -4; }, "device_ns");
  rejected([](nlohmann::json* m) { (*m)["frames"][0] = 7; }, "frames[0]");
  rejected([](nlohmann::json* m) { (*m)["units"][1]["name"] = "left"; }, "appears twice");
  rejected([](nlohmann::json* m) { (*m)["units"][0] = "left"; }, "units[0]");
  rejected([](nlohmann::json* m) { m->erase("frames"); }, "lacks 'units' or 'frames'");
  rejected([](nlohmann::json* m) { (*m)["format"] = "other"; }, "not a hovs dataset manifest");
}

}  // namespace
}  // namespace hovs
