#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "core/io.h"

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

}  // namespace
}  // namespace hovs
