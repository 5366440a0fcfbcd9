#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <functional>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/manifest.h"
#include "core/shard_set.h"
#include "core/yaml_reader.h"

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

TEST(Io, StagingLeftByAKilledRunIsRemovedWhenTheNextOneCommits) {
  // A run killed before its destructor (Ctrl-C, a crash) leaves its hidden staging folder; the next run for the
  // same target removes it when it commits and the process is gone, and leaves a live process's folder and other
  // names alone. A run that fails (never commits) removes nothing of it.
  const fs::path root = TempRoot();
  const fs::path dead = root / ".report.partial-999999999-1-0";  // beyond any pid_max: no such process
  const fs::path dead_old = root / ".report.old-999999999-2-0";
  const fs::path live = root / (".report.partial-" + std::to_string(::getpid()) + "-3-0");
  const fs::path other = root / ".other.partial-999999999-4-0";
  for (const auto& p : {dead, dead_old, live, other}) fs::create_directories(p / "images");
  {
    StagedDirectory failing(root / "report", "test");  // destroyed without Commit: an error
  }
  EXPECT_TRUE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(dead_old));
  {
    StagedDirectory stage(root / "report", "test");
    EXPECT_TRUE(fs::exists(stage.staging()));
    stage.Commit();
  }
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_FALSE(fs::exists(dead_old));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(other));
  fs::remove_all(root);
}

TEST(Io, AResumeThatFailsKeepsWhatTheKilledRunKept) {
  // The folder a killed run kept is adopted by a resume; if that run fails (its configuration refused, say), the
  // folder stays, under its own name, for the next resume, with everything in it; a plain run that fails leaves it
  // too; the run that commits takes it.
  const fs::path root = TempRoot();
  const fs::path kept = root / ".set.partial-999999999-1-0";
  fs::create_directories(kept);
  WriteOutputMarker(kept, "dataset");
  WriteFileAtomic(kept / "frames.jsonl", "kept frames");
  const auto staging_folders = [&] {
    std::vector<fs::path> found;
    for (const auto& e : fs::directory_iterator(root))
      if (e.path().filename().string().rfind(".set.partial-", 0) == 0) found.push_back(e.path());
    return found;
  };
  for (int attempt = 0; attempt < 2; ++attempt) {
    pid_t child = fork();  // each attempt in a process of its own, which then ends (a refused command)
    ASSERT_GE(child, 0);
    if (child == 0) {
      try {
        StagedDirectory stage(root / "set", "dataset", {}, false, /*resume=*/true);
        if (!stage.resumed() || ReadFile(stage.staging() / "frames.jsonl") != "kept frames") _exit(3);
        throw Error("test", "made with another configuration");
      } catch (const Error&) { _exit(0); }
      _exit(4);
    }
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "attempt " << attempt << " status " << status;
    const auto found = staging_folders();
    ASSERT_EQ(found.size(), 1u) << "attempt " << attempt;
    EXPECT_EQ(ReadFile(found[0] / "frames.jsonl"), "kept frames") << "attempt " << attempt;
  }
  {
    StagedDirectory plain(root / "set", "dataset");  // without --resume, failing
  }
  EXPECT_EQ(staging_folders().size(), 1u);
  {
    StagedDirectory stage(root / "set", "dataset", {}, false, /*resume=*/true);
    EXPECT_TRUE(stage.resumed());
    stage.Commit();
  }
  EXPECT_TRUE(staging_folders().empty());
  EXPECT_EQ(ReadFile(root / "set" / "frames.jsonl"), "kept frames");
  fs::remove_all(root);
}

TEST(Io, ReadersVerifyTheChecksumsARecordVouchesFor) {
  const fs::path root = TempRoot();
  WriteFileAtomic(root / "a.png", "the image");
  ExpectChecksum(root / "a.png", TextChecksum("the image"), "dataset.json");
  EXPECT_EQ(ReadFile(root / "a.png"), "the image");
  WriteFileAtomic(root / "a.png", "the imagE");
  try {
    ReadFile(root / "a.png");
    ADD_FAILURE() << "a tampered file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does not match its checksum in dataset.json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(VerifyExpectedChecksum(root / "a.png"), Error);
  EXPECT_EQ(FileChecksum(root / "a.png"), TextChecksum("the imagE"));
  ClearNotedInputs();  // forgets the expectation
  EXPECT_EQ(ReadFile(root / "a.png"), "the imagE");
  fs::remove_all(root);
}

TEST(Io, TextFromOtherSystemsReadsAsWritten) {
  EXPECT_EQ(NormalisedText("\xEF\xBB\xBF"
                           "a\r\nb\rc\n\rd"),
            "a\nb\nc\n\nd");
  EXPECT_EQ(NormalisedText("plain\n"), "plain\n");
  const fs::path root = TempRoot();
  fs::create_directories(root / "folder");
  try {
    RequireFile(root / "folder", "a scene file");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder, not a scene file"), std::string::npos);
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
  // Checksums in the writer's form, of files inside the manifest's folder (a frame may name files without one).
  const std::string sum = "fnv1a64:0123456789abcdef";
  const auto with_sums = [&](nlohmann::json* m) { (*m)["frames"][1]["checksums"] = {{"images/l1.png", sum}}; };
  {
    nlohmann::json m = ok;
    with_sums(&m);
    EXPECT_NO_THROW(CheckDatasetManifest(m, "m.json"));
  }
  rejected([&](nlohmann::json* m) { with_sums(m), (*m)["frames"][1]["checksums"]["images/l1.png"] = "fnv1a64:xyz"; },
           "16 hex digits");
  rejected([&](nlohmann::json* m) { with_sums(m), (*m)["frames"][1]["checksums"]["../x.png"] = sum; },
           "leaves the file's folder");
}

TEST(Shards, ShardTextAndRecordsAreReadStrictly) {
  int index = -1, count = -1;
  ParseShardSpec("3/8", "--shard", &index, &count);
  EXPECT_EQ(index, 3);
  EXPECT_EQ(count, 8);
  // A wrap-around of 2^32 once ran the whole job as shard 0 of 1.
  for (const char* bad :
       {"4294967296/4294967297", "-1/2", "2/2", "1/0", " 1/2", "1/2x", "1//2", "1", "/", "1e3/2000", "0/100001"})
    EXPECT_NE(ErrorOf([&] { ParseShardSpec(bad, "--shard", &index, &count); }).find("--shard"), std::string::npos)
        << bad;
  // Records: a count of 2e9 is refused before anything is allocated; a malformed record names the file.
  const auto doc = [](const nlohmann::json& shard) { return nlohmann::json{{"seed", 1}, {"shard", shard}}; };
  const std::vector<fs::path> files = {"a.json", "b.json"};
  EXPECT_EQ(OrderShards({doc({{"index", 1}, {"count", 2}}), doc({{"index", 0}, {"count", 2}})}, files),
            (std::vector<size_t>{1, 0}));
  for (const nlohmann::json& bad :
       {nlohmann::json{{"index", 0}, {"count", 2000000000}}, nlohmann::json{{"index", 0}},
        nlohmann::json{{"index", "0"}, {"count", 2}}, nlohmann::json{{"index", 0.5}, {"count", 2}},
        nlohmann::json{{"index", 2}, {"count", 2}}, nlohmann::json(7)}) {
    const std::string e = ErrorOf([&] { OrderShards({doc(bad), doc({{"index", 1}, {"count", 2}})}, files); });
    EXPECT_NE(e.find("a.json"), std::string::npos) << bad.dump() << ": " << e;
  }
  EXPECT_NE(ErrorOf([&] {
              OrderShards({doc({{"index", 0}, {"count", 100000}}), doc({{"index", 1}, {"count", 100000}})}, files);
            }).find("shard 2 of 100000 is missing"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              OrderShards({doc({{"index", 0}, {"count", 2}}), doc({{"index", 0}, {"count", 2}})}, files);
            }).find("given twice"),
            std::string::npos);
}

}  // namespace
}  // namespace hovs

namespace hovs {
namespace {

TEST(Yaml, MissingAndRepeatedKeysAreNamed) {
  const YamlReader r("scene.yaml");
  // A key given twice anywhere (yaml-cpp keeps both and a lookup finds one) is refused with its line.
  EXPECT_NE(ErrorOf([&] { r.Load("a: 1\nb:\n  c: 2\n  c: 3\n"); }).find("scene.yaml:4 (b.c)"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.Load("l:\n  - {x: 1, x: 2}\n"); }).find("duplicate key 'x'"), std::string::npos);
  // A missing key is named, not yaml-cpp's "invalid node".
  const YAML::Node root = r.Load("camera: {width: 10}\n");
  const YAML::Node& camera = root["camera"];
  YAML::Node v;
  EXPECT_NE(ErrorOf([&] { r.Require(camera, "camera", "height", &v); }).find("missing 'camera.height'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.Number(camera["height"], "camera.height"); }).find("missing 'camera.height'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.String(root["name"], "name"); }).find("missing 'name'"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.Integer(r.Load("n: 1000000000")["n"], "n"); }).find("below 1000000000"), std::string::npos);
  EXPECT_EQ(r.Integer(r.Require(camera, "camera", "width", &v), "camera.width"), 10);
}

}  // namespace
}  // namespace hovs
