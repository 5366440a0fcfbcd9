#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <functional>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/manifest.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

fs::path TempRoot() {
  const fs::path p =
      fs::temp_directory_path() / ("hovs-io-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                   "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
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
    StagedDirectory stage(target, "test");
    WriteFileAtomic(stage.staging() / "x.json", "{}");
    // No commit: an error happened.
  }
  EXPECT_FALSE(fs::exists(target));
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(root)) ++entries;
  EXPECT_EQ(entries, 0) << "the staging folder is removed";
  {
    StagedDirectory stage(target, "test");
    WriteFileAtomic(stage.staging() / "x.json", "{\"v\": 1}");
    stage.Commit();
  }
  EXPECT_TRUE(fs::exists(target / "x.json"));
  {
    StagedDirectory stage(target, "test");
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
  const fs::path dead = root / ".report.partial-999999999-1-0";  // beyond any pid_max: no such process
  const fs::path dead_old = root / ".report.old-999999999-2-0";
  const fs::path live = root / (".report.partial-" + std::to_string(::getpid()) + "-3-0");
  const fs::path other = root / ".other.partial-999999999-4-0";
  for (const auto& p : {dead, dead_old, live, other}) fs::create_directories(p / "images");
  {
    StagedDirectory stage(root / "report", "test");
    EXPECT_FALSE(fs::exists(dead));
    EXPECT_FALSE(fs::exists(dead_old));
    EXPECT_TRUE(fs::exists(live));
    EXPECT_TRUE(fs::exists(other));
    EXPECT_TRUE(fs::exists(stage.staging()));
  }
  fs::remove_all(root);
}

// The message of the Error that f throws (empty if it throws none).
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) { return e.what(); }
  return "";
}

TEST(Io, OutputFoldersReplaceOnlyTheSameCommandsEarlierOutput) {
  const fs::path root = TempRoot();
  // A new folder, an empty one, and an earlier output of the same command may be written.
  EXPECT_NO_THROW(CheckOutputFolder(root / "new", "render"));
  fs::create_directories(root / "empty");
  EXPECT_NO_THROW(CheckOutputFolder(root / "empty", "render"));
  {
    StagedDirectory stage(root / "report", "render");
    WriteFileAtomic(stage.staging() / "a.json", "{}");
    stage.Commit();
  }
  EXPECT_TRUE(fs::exists(root / "report" / kOutputMarker));
  EXPECT_NO_THROW(CheckOutputFolder(root / "report", "render"));
  // Everything else is refused, and the refusal names the folder and why.
  EXPECT_NE(ErrorOf([&] { CheckOutputFolder(root / "report", "calibrate"); }).find("output of 'hovs render'"),
            std::string::npos);
  WriteFileAtomic(root / "config.yaml", "a: 1\n");
  EXPECT_NE(ErrorOf([&] { CheckOutputFolder(root / "config.yaml", "design"); }).find("not a folder"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf([&] { CheckOutputFolder(root / "config.yaml", "design", {root / "config.yaml"}); }).find("is an input"),
      std::string::npos);
  fs::create_directories(root / "user");
  WriteFileAtomic(root / "user" / "notes.txt", "mine");
  EXPECT_NE(ErrorOf([&] { CheckOutputFolder(root / "user", "render"); }).find("did not write"), std::string::npos);
  fs::create_directory_symlink(root / "report", root / "link");
  EXPECT_NE(ErrorOf([&] { CheckOutputFolder(root / "link", "render"); }).find("symbolic link"), std::string::npos);
  // An earlier output that holds an input of this run (given, or read through ReadFile) is refused.
  EXPECT_NE(ErrorOf([&] {
              CheckOutputFolder(root / "report", "render", {root / "report" / "a.json"});
            }).find("holds the input"),
            std::string::npos);
  ReadFile(root / "report" / "a.json");
  EXPECT_NE(ErrorOf([&] { CheckOutputFolder(root / "report", "render"); }).find("holds the input"), std::string::npos);
  // A folder that holds the current directory.
  const fs::path cwd = fs::current_path();
  fs::current_path(root / "empty");
  const std::string dot = ErrorOf([&] { CheckOutputFolder(".", "render"); });
  const std::string up = ErrorOf([&] { CheckOutputFolder("..", "render"); });
  fs::current_path(cwd);
  EXPECT_NE(dot.find("current directory"), std::string::npos) << dot;
  EXPECT_NE(up.find("current directory"), std::string::npos) << up;
  // The refused folders are untouched.
  EXPECT_EQ(ReadFile(root / "user" / "notes.txt"), "mine");
  EXPECT_EQ(ReadFile(root / "config.yaml"), "a: 1\n");
  fs::remove_all(root);
}

TEST(Json, DuplicateKeysAndBadNumbersAreNamedErrors) {
  EXPECT_EQ(ParseJson(R"({"a": {"b": 1, "c": [1, 2]}, "d": 2})", "x.json")["a"]["c"][1], 2);
  EXPECT_NE(ErrorOf([] { ParseJson("{\"cx\": 1,\n \"cx\": 2}", "m.json"); }).find("m.json: the key 'cx' appears twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseJson("{\"a\": {\"b\": 1, \"b\": 1}}", "m.json"); }).find("'b' appears twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseJson("{\"a\":\n  [1, 2,,]}", "m.json"); }).find("line 2"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseJson("{\"a\": 1e999}", "m.json"); }).find("m.json: not valid JSON"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseJson(std::string(300, '[') + std::string(300, ']'), "m.json"); }).find("nested deeper"),
            std::string::npos);
}

TEST(Io, PathsInFilesStayInTheirFolder) {
  EXPECT_EQ(ContainedPath("data", "images/a.png", "m.json"), fs::path("data/images/a.png"));
  EXPECT_THROW(ContainedPath("data", "/etc/passwd", "m.json"), Error);
  EXPECT_THROW(ContainedPath("data", "../secret.png", "m.json"), Error);
  EXPECT_THROW(ContainedPath("data", "images/../../x.png", "m.json"), Error);
  EXPECT_THROW(ContainedPath("data", "", "m.json"), Error);
}

TEST(Manifest, MalformedFieldsAreNamedErrors) {
  // A rendered set's shape (ground truth present) and a capture's (device_ns, no ground truth) are accepted.
  const nlohmann::json ok = nlohmann::json::parse(R"({"format": "hovs-dataset", "version": 1,
    "units": [{"name": "left"}, {"name": "right"}],
    "frames": [{"id": 0, "views": [{"unit": "left", "image": "images/l.png", "ground_truth": {"exr": "t/l.exr", "sidecar": "t/l.json"}},
                                   {"unit": "right", "image": "images/r.png", "device_ns": 123456789}]},
               {"id": 1, "views": [{"unit": "left", "image": "images/l1.png", "width": 640, "height": 480}]}]})");
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
  // Garbage that once went through: paths out of the folder, unknown keys and versions, repeated frame ids, sizes.
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][0]["image"] = "/etc/passwd"; }, "absolute");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][0]["image"] = "../../x.png"; },
           "leaves the file's folder");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][0]["ground_truth"]["exr"] = "/tmp/t.exr"; }, "absolute");
  rejected([](nlohmann::json* m) { (*m)["framez"] = 1; }, "unknown key 'framez'");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][0]["imgae"] = "x"; }, "unknown key 'imgae'");
  rejected([](nlohmann::json* m) { (*m)["version"] = 7; }, "version");
  rejected([](nlohmann::json* m) { m->erase("version"); }, "version");
  rejected([](nlohmann::json* m) { (*m)["frames"][1]["id"] = 0; }, "appears twice");
  rejected([](nlohmann::json* m) { (*m)["frames"][1].erase("id"); }, "frames[1].id");
  rejected([](nlohmann::json* m) { (*m)["frames"][1]["views"][0]["width"] = 0; }, "width");
  rejected([](nlohmann::json* m) { (*m)["frames"][0]["views"][1]["unit"] = "left"; }, "second view");
  rejected([](nlohmann::json* m) { (*m)["units"][0]["name"] = ""; }, "non-empty");
}

}  // namespace
}  // namespace hovs
