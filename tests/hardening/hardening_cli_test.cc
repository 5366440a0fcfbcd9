// Bad input through the command line, one test per class of defect: data loss (outputs over inputs, files or
// unrecognised folders; interrupted runs), memory safety on files users exchange, resources (declared sizes,
// file system refusals), garbage in (truncated images, noise, absurd models, malformed manifests and tables),
// and messages (one line naming the input, exit 2). Each case runs the hovs executable on inputs this test makes
// from a small rendered set.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/io.h"
#include "io/image_io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

const std::string kScenes = std::string(HOVS_SOURCE_DIR) + "/scenes";

// Every regular file under a folder with its content: an "earlier report" compared before and after a run.
std::map<std::string, std::string> Tree(const fs::path& root) {
  std::map<std::string, std::string> t;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file()) t[fs::relative(e.path(), root).string()] = ReadFile(e.path());
  return t;
}

int Lines(const std::string& s) {
  int n = 0;
  std::string line;
  for (char c : s) {
    if (c == '\n' || c == '\r') {
      n += !line.empty();
      line.clear();
    } else {
      line += c;
    }
  }
  return n + !line.empty();
}

// CRC-32 of PNG chunks (to write a header that is intact but declares an impossible size).
uint32_t Crc32(const std::string& s) {
  uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : s) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

std::string Chunk(const std::string& type, const std::string& data) {
  const auto be = [](uint32_t v) { return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; };
  return be(uint32_t(data.size())) + type + data + be(Crc32(type + data));
}

// The small inputs every case starts from (rendered once per test program run, at 1/5 of the resolution).
class Hardening : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test::Scratch("hardening", "fixtures"));
    fs::create_directories(*dir_);
    const auto r = test::Hovs("-q dataset --kind mono_calibration --scene " + kScenes +
                              "/reference_calibration.yaml --count 4 --samples 1 --downscale 5 --out " +
                              (*dir_ / "mono").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto s = test::Hovs("-q render --scene " + kScenes + "/street.yaml --samples 1 --downscale 10 --out " +
                              (*dir_ / "street").string());
    ASSERT_EQ(s.exit_code, 0) << s.output;
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_->parent_path());
    delete dir_;
  }
  static fs::path Mono() { return *dir_ / "mono" / "dataset.json"; }
  static fs::path Street() { return *dir_ / "street" / "dataset.json"; }
  static fs::path Image() { return *dir_ / "mono" / "images" / "unit0_0000.png"; }
  static fs::path Work(const std::string& name) {
    const fs::path p = *dir_ / name;
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }

  // One bad command line: exit 2 within the time bound, exactly one line of output, naming `needle`.
  static void Refused(const std::string& args, const std::string& needle, int seconds = 60) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r =
        test::Run("timeout -s KILL " + std::to_string(seconds) + " " + std::string(HOVS_BINARY) + " " + args);
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.exit_code, 2) << "hovs " << args << "\n" << r.output;
    EXPECT_LT(took, seconds) << "hovs " << args << " did not end";
    EXPECT_EQ(Lines(r.output), 1) << "hovs " << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << "hovs " << args << "\n" << r.output;
  }

  static fs::path* dir_;
};
fs::path* Hardening::dir_ = nullptr;

TEST_F(Hardening, OutputsNeverReplaceFilesInputsOrFoldersHovsDidNotWrite) {
  const fs::path w = Work("outputs");
  const std::string config = (w / "config.yaml").string();
  fs::copy_file(std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml", config);
  fs::create_directories(w / "mine");
  WriteFileAtomic(w / "mine" / "notes.txt", "mine");
  const auto before_config = ReadFile(config);
  const auto before_inputs = Tree(Mono().parent_path());
  const std::string render = "render --scene " + kScenes + "/reference_board.yaml --samples 1 --downscale 10 --out ";
  Refused("design --config " + config + " --out " + config, "config.yaml");  // a file, the input
  Refused("calibrate --dataset " + Mono().string() + " --out " + Mono().parent_path().string(), "input");  // holds it
  Refused(render + (w / "mine").string(), "did not write");                 // unrecognised
  Refused(render + Mono().parent_path().string(), "not of 'hovs render'");  // another command's
  Refused("unwrap --model " + Mono().string() + " --input " + Image().string() + " --out " + w.string() +
              "/u --save-map " + config,
          "not a hovs mapping file");  // a file output
  Refused("capture --replay " + Mono().parent_path().string() + "/images --out " + (w / "mine").string(), "mine");
  {
    // The working directory and what holds it.
    const fs::path cwd = fs::current_path();
    fs::current_path(w / "mine");
    const auto dot = test::Hovs(render + ".");
    const auto up = test::Hovs(render + "..");
    const auto validate = test::Hovs("validate --preset reduced --out .");
    fs::current_path(cwd);
    for (const auto& r : {dot, up, validate}) {
      EXPECT_EQ(r.exit_code, 2) << r.output;
      EXPECT_NE(r.output.find("current directory"), std::string::npos) << r.output;
    }
  }
  EXPECT_EQ(ReadFile(config), before_config);
  EXPECT_EQ(ReadFile(w / "mine" / "notes.txt"), "mine");
  EXPECT_EQ(Tree(Mono().parent_path()), before_inputs);
  // An earlier output of the same command is replaced by a successful run, and kept byte for byte by a failed one.
  ASSERT_EQ(test::Hovs("-q " + render + (w / "r").string()).exit_code, 0);
  const auto earlier = Tree(w / "r");
  EXPECT_EQ(earlier.count(kOutputMarker), 1u);
  Refused("render --scene " + config + " --out " + (w / "r").string(), "config.yaml");
  Refused(render + (w / "r").string() + " --samples 0", "--samples");
  EXPECT_EQ(Tree(w / "r"), earlier);
  for (const auto& e : fs::directory_iterator(w))
    EXPECT_EQ(e.path().filename().string().find(".r."), std::string::npos) << "left behind: " << e.path();
}

TEST_F(Hardening, AnInterruptedRunLeavesNoStagingBehind) {
  const fs::path w = Work("interrupt");
  const fs::path log = w / "log.txt";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string out = (w / "set").string(), scene = kScenes + "/reference_calibration.yaml";
    std::freopen(log.c_str(), "w", stderr);
    execl(HOVS_BINARY, HOVS_BINARY, "-q", "dataset", "--kind", "mono_calibration", "--scene", scene.c_str(), "--count",
          "40", "--samples", "4", "--out", out.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until the run writes into its staging folder, then interrupt it as Ctrl-C would.
  bool staging = false;
  for (int k = 0; k < 300 && !staging; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (const auto& e : fs::directory_iterator(w))
      staging = staging || e.path().filename().string().find(".set.partial-") == 0;
  }
  ASSERT_TRUE(staging) << ReadFile(log);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << "status " << status;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(w))
    if (e.path().filename() != "log.txt") left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << "left behind: " << (left.empty() ? "" : left[0]);
}

TEST_F(Hardening, FilesWithImpossibleSizesAreRefusedBeforeTheyAreRead) {
  const fs::path w = Work("sizes");
  // An intact PNG header declaring 60000 x 60000 pixels, in 57 bytes.
  const std::string ihdr = {0, 0, char(0xea), 0x60, 0, 0, char(0xea), 0x60, 8, 0, 0, 0, 0};
  WriteFileAtomic(w / "huge.png", std::string("\x89PNG\r\n\x1a\n", 8) + Chunk("IHDR", ihdr) + Chunk("IEND", ""));
  Refused("position -i " + (w / "huge.png").string() + " --design " + Mono().string() + " --out " + (w / "p").string(),
          "huge.png");
  Refused(
      "unwrap --model " + Mono().string() + " --input " + (w / "huge.png").string() + " --out " + (w / "u").string(),
      "huge.png");
  // An option that would make a library allocate without bound, and a ground-truth image of the wrong size.
  Refused("depth --dataset " + Street().string() + " --num-disparities 1024000 --out " + (w / "d").string(),
          "--num-disparities", 20);
  {
    fs::copy(Street().parent_path(), w / "street", fs::copy_options::recursive);
    const auto m = nlohmann::json::parse(ReadFile(w / "street" / "dataset.json"));
    const auto exr = w / "street" / m["frames"][0]["views"][0]["ground_truth"]["exr"].get<std::string>();
    const std::vector<float> z(8 * 6 * 12, 1.0f);
    io::WriteExr(exr, 8, 6, {"Z", "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "id", "mask", "M.X", "M.Y", "M.Z"},
                 z.data(), {});
    // A file that does not match the manifest's checksum is refused as such; one whose checksum was made to match
    // is refused for its size.
    Refused("depth --dataset " + (w / "street" / "dataset.json").string() + " --out " + (w / "d").string(),
            "does not match its checksum");
    nlohmann::json edited = m;
    edited["frames"][0]["checksums"][m["frames"][0]["views"][0]["ground_truth"]["exr"].get<std::string>()] =
        FileChecksum(exr);
    WriteFileAtomic(w / "street" / "dataset.json", edited.dump(1));
    Refused("depth --dataset " + (w / "street" / "dataset.json").string() + " --out " + (w / "d").string(),
            "the ground truth is 8 x 6");
  }
  // File system refusals are bad input too: one line naming the path.
  Refused("render --scene " + kScenes + "/reference_board.yaml --samples 1 --downscale 10 --out /proc/hovs/x", "/proc");
}

TEST_F(Hardening, DamagedImagesAndNoiseGiveErrorsNotResults) {
  const fs::path w = Work("garbage");
  // Truncated PNG and JPEG: the decoders' complaints are errors naming the file.
  const std::string png = ReadFile(Image());
  WriteFileAtomic(w / "cut.png", png.substr(0, png.size() / 2));
  int iw = 0, ih = 0, ic = 0;
  const auto px = io::ReadImage(Image(), &iw, &ih, &ic);
  io::WriteImage(w / "full.jpg", iw, ih, ic, px, 8);
  const std::string jpg = ReadFile(w / "full.jpg");
  WriteFileAtomic(w / "cut.jpg", jpg.substr(0, jpg.size() / 2));
  for (const char* f : {"cut.png", "cut.jpg"})
    Refused("position -i " + (w / f).string() + " --design " + Mono().string() + " --out " + (w / "p").string(), f);
  // Noise: no rim, no board.
  std::vector<float> noise(size_t(iw) * ih);
  uint32_t state = 12345;
  for (float& v : noise) state = state * 1664525u + 1013904223u, v = float(state >> 8) / float(1 << 24);
  fs::create_directories(w / "noise");
  for (int k = 0; k < 3; ++k) io::WriteImage(w / "noise" / ("n" + std::to_string(k) + ".png"), iw, ih, 1, noise, 8);
  Refused("position -i " + (w / "noise" / "n0.png").string() + " --design " + Mono().string() + " --out " +
              (w / "p").string(),
          "no rim");
  Refused("calibrate --images " + (w / "noise").string() + " --board 7x5x0.03 --out " + (w / "c").string(), "no board");
}

TEST_F(Hardening, AbsurdModelsManifestsAndTablesAreRefusedByName) {
  const fs::path w = Work("models");
  ASSERT_EQ(test::Hovs("-q calibrate --dataset " + Mono().string() + " --out " + (w / "cal").string()).exit_code, 0);
  const auto cal = nlohmann::json::parse(ReadFile(w / "cal" / "calibration.json"));
  const auto model = [&](const std::string& name, const std::function<void(nlohmann::json*)>& edit) {
    nlohmann::json c = cal;
    edit(&c);
    WriteFileAtomic(w / name, c.dump());
    return (w / name).string();
  };
  const std::string input = " --input " + Image().string() + " --out " + (w / "u").string();
  Refused("unwrap --model " +
              model("zero.json",
                    [](auto* c) {
                      (*c)["polynomial"]["poly"] = {0, 0, 0, 0, 0};
                    }) +
              input,
          "a0 must be non-zero");
  Refused("unwrap --model " + model("far.json", [](auto* c) { (*c)["polynomial"]["cx"] = 1e9; }) + input,
          "far outside");
  Refused("unwrap --model " + model("huge.json", [](auto* c) { (*c)["polynomial"]["c"] = 1e308; }) + input, "affine");
  {
    std::string text = cal.dump();
    text.replace(text.find("\"cx\":"), 5, "\"cx\": 1, \"cx\":");
    WriteFileAtomic(w / "dup.json", text);
    Refused("unwrap --model " + (w / "dup.json").string() + input, "appears twice");
  }
  // Manifests: paths out of the dataset's folder, unknown keys and versions.
  const auto manifest = nlohmann::json::parse(ReadFile(Mono()));
  const auto variant = [&](const std::string& name, const std::function<void(nlohmann::json*)>& edit) {
    fs::copy(Mono().parent_path(), w / name, fs::copy_options::recursive);
    nlohmann::json m = manifest;
    edit(&m);
    WriteFileAtomic(w / name / "dataset.json", m.dump());
    return (w / name / "dataset.json").string();
  };
  const std::string out = " --out " + (w / "c").string();
  Refused("calibrate --dataset " +
              variant("abs", [](auto* m) { (*m)["frames"][0]["views"][0]["image"] = "/etc/passwd"; }) + out,
          "absolute");
  Refused("calibrate --dataset " +
              variant("up", [](auto* m) { (*m)["frames"][0]["views"][0]["image"] = "../../x.png"; }) + out,
          "leaves the file's folder");
  Refused("calibrate --dataset " + variant("key", [](auto* m) { (*m)["framez"] = 1; }) + out, "unknown key 'framez'");
  Refused("calibrate --dataset " + variant("ver", [](auto* m) { (*m)["version"] = 9; }) + out, "version");
  Refused("calibrate --dataset " + variant("ids", [](auto* m) { (*m)["frames"][1]["id"] = 0; }) + out, "appears twice");
  Refused("calibrate --dataset " +
              variant("board",
                      [](auto* m) {
                        (*m)["boards"][0]["inner_corners"] = {1000000000, 5};
                      }) +
              out,
          "inner_corners");
  // Corner tables: a row given twice.
  WriteFileAtomic(w / "twice.csv",
                  "image,corner,board_x_mm,board_y_mm,u_px,v_px\na.png,0,0,0,10,10\na.png,0,0,0,10,10\n");
  Refused("calibrate --corners " + (w / "twice.csv").string() + " --size 640x480" + out, "twice.csv:3");
  // Scenes: a negative seed, two units of one name.
  std::string board = ReadFile(kScenes + "/reference_board.yaml");
  board.replace(board.find("seed: 1,"), 8, "seed: -1,");
  WriteFileAtomic(w / "seed.yaml", board);
  Refused("render --scene " + (w / "seed.yaml").string() + out, "seed");
  std::string stereo = ReadFile(kScenes + "/reference_stereo.yaml");
  stereo.replace(stereo.find("name: right"), 11, "name: left");
  WriteFileAtomic(w / "twins.yaml", stereo);
  Refused("render --scene " + (w / "twins.yaml").string() + out, "a second unit named 'left'");
  // Two input images of one name would write the same views.
  fs::create_directories(w / "two");
  fs::copy_file(Image(), w / "two" / "a.png");
  int iw = 0, ih = 0, ic = 0;
  const auto px = io::ReadImage(Image(), &iw, &ih, &ic);
  io::WriteImage(w / "two" / "a.jpg", iw, ih, ic, px, 8);
  Refused("unwrap --model " + Mono().string() + " --input " + (w / "two").string() + " --out " + (w / "u").string(),
          "two images named 'a'");
}

TEST_F(Hardening, OptionsAndCommandsAreNamedInOneLine) {
  const fs::path w = Work("options");
  Refused("frobnicate", "unknown command 'frobnicate'");
  // A command's own error names the command once.
  Refused("unwrap --input " + Image().string() + " --out " + (w / "u").string(),
          "hovs unwrap: error: give either --model or --map");
  Refused("--frob render", "unknown option '--frob'");
  for (const std::string v : {"nan", "inf", "-1", "1e12"})
    Refused("depth --dataset " + Street().string() + " --sigma-disparity " + v + " --out " + (w / "d").string(),
            "--sigma-disparity");
  Refused("unwrap --model " + Mono().string() + " --input " + Image().string() + " --scene-distance nan --out " +
              (w / "u").string(),
          "--scene-distance");
  Refused("capture --replay " + Mono().parent_path().string() + "/images --region 0x0+0+0 --out " + (w / "c").string(),
          "--region");
  Refused(
      "position -i " + Image().string() + " --design " + Mono().string() + " --search inf --out " + (w / "p").string(),
      "--search");
}

TEST_F(Hardening, TamperedOrForeignInputsNeverPassForTheOnesTheirRecordsName) {
  const fs::path w = Work("tampered");
  // An image changed after its manifest recorded it: every reader verifies the bytes it reads.
  fs::copy(Mono().parent_path(), w / "mono", fs::copy_options::recursive);
  const auto m = nlohmann::json::parse(ReadFile(w / "mono" / "dataset.json"));
  const fs::path image = w / "mono" / m["frames"][0]["views"][0]["image"].get<std::string>();
  std::string bytes = ReadFile(image);
  bytes[bytes.size() / 2] ^= 0x01;
  WriteFileAtomic(image, bytes);
  Refused("calibrate --dataset " + (w / "mono" / "dataset.json").string() + " --out " + (w / "c").string(),
          "does not match its checksum");
  WriteFileAtomic(image, ReadFile(Image()));
  // Sidecar corners of a status hovs never writes, or of an id beyond the board (their checksum made to match).
  const std::string sidecar_rel = m["frames"][0]["views"][0]["ground_truth"]["sidecar"];
  const fs::path sidecar = w / "mono" / sidecar_rel;
  const std::string good_sidecar = ReadFile(sidecar);
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, nlohmann::json>>{{"status", "bogus"}, {"id", 99999}}) {
    nlohmann::json side = nlohmann::json::parse(good_sidecar);
    side["boards"][0]["corners"][0][key] = value;
    WriteFileAtomic(sidecar, side.dump());
    nlohmann::json edited = m;
    edited["frames"][0]["checksums"][sidecar_rel] = FileChecksum(sidecar);
    WriteFileAtomic(w / "mono" / "dataset.json", edited.dump());
    Refused("calibrate --dataset " + (w / "mono" / "dataset.json").string() + " --truth-corners --out " +
                (w / "c").string(),
            key == "status" ? "status 'bogus'" : ".id: expected a whole number in 0..34 (got 99999)");
  }
}

TEST_F(Hardening, CapturesThatFailLeaveNothingAndReplaysKeepOneSize) {
  const fs::path w = Work("capture");
  // A replay whose second image has another size (a camera's frames keep one).
  fs::create_directories(w / "frames");
  const std::vector<float> one(1, 0.5f), six(6, 0.5f);
  io::WriteImage(w / "frames" / "a.png", 1, 1, 1, one, 8);
  io::WriteImage(w / "frames" / "b.png", 3, 2, 1, six, 8);
  Refused("capture --replay " + (w / "frames").string() + " --frames 2 --out " + (w / "c").string(), "b.png");
  const auto kept = nlohmann::json::parse(ReadFile(w / "c" / "dataset.json"));  // the first frame stays, said so
  EXPECT_EQ(kept["frames"].size(), 1u);
  EXPECT_NE(kept["status"].get<std::string>().find("stopped by an error after 1 frames"), std::string::npos);
  // A capture that fails before its first frame leaves nothing, and the same --out takes a good capture after.
  fs::create_directories(w / "broken");
  WriteFileAtomic(w / "broken" / "a.png", "\x89PNG not an image");
  Refused("capture --replay " + (w / "broken").string() + " --frames 1 --out " + (w / "d").string(), "a.png");
  EXPECT_FALSE(fs::exists(w / "d")) << "a capture that failed after 0 frames left its folder";
  const auto good = test::Hovs("-q capture --replay " + Mono().parent_path().string() + "/images --frames 1 --out " +
                               (w / "d").string());
  EXPECT_EQ(good.exit_code, 0) << good.output;
  // The simulator's packet loss is bounded by the command line where the simulator bounds it.
  Refused("capture --simulate " + Mono().string() + " --simulate-loss 0.9 --frames 1 --out " + (w / "c").string(),
          "--simulate-loss");
}

TEST_F(Hardening, OptionsAndFilesOfTheWrongKindAreNamed) {
  const fs::path w = Work("kinds");
  ASSERT_EQ(test::Hovs("-q calibrate --dataset " + Mono().string() + " --out " + (w / "cal").string()).exit_code, 0);
  const std::string cal = (w / "cal" / "calibration.json").string();
  // A folder where a file is expected, a PNG given as a model, an image size that is not the model's.
  fs::create_directories(w / "folder");
  Refused("design --config " + (w / "folder").string() + " --out " + (w / "d").string(), "is a folder, not");
  Refused("tolerance -c " + (w / "folder").string() + " --out " + (w / "t").string(), "is a folder, not");
  Refused("unwrap --model " + Image().string() + " --input " + Image().string() + " --out " + (w / "u").string(),
          "is an image, not a camera model");
  Refused("convert " + cal + " --to kalibr --image-size 100x100 --out " + (w / "k").string(),
          "is for 550 x 440 images, not 100 x 100");
  // A camera name that would write a second YAML key, a ROS 2 namespace that is not one.
  Refused("convert " + cal + " --to mei --camera-name 'a\nimage_width: 5' --out " + (w / "k").string(),
          "--camera-name");
  for (const char* prefix : {"1bad", "a//b", "a/", "a b", "ns/2x", "a__b"})
    Refused("live --simulate " + Mono().string() + " --model " + Mono().string() + " --publish --topic-prefix '" +
                prefix + "' -n 1 --out " + (w / "l").string(),
            "--topic-prefix");
  // I/N parsed strictly: 2^32 once wrapped to shard 0 of 1 and ran the whole job.
  Refused("dataset --scene " + kScenes + "/reference_calibration.yaml --count 2 --shard 4294967296/4294967297 --out " +
              (w / "s").string(),
          "--shard");
  Refused("tolerance -c " + std::string(HOVS_SOURCE_DIR) + "/study/reference.yaml --shard 1/2/3 --out " +
              (w / "t").string(),
          "--shard");
  // A required key missing from a scene is named (not yaml-cpp's "invalid node").
  std::string scene = ReadFile(kScenes + "/reference_board.yaml");
  const size_t unit = scene.find("units:");
  ASSERT_NE(unit, std::string::npos);
  WriteFileAtomic(w / "scene.yaml", scene);
  const auto r = test::Hovs("render --scene " + (w / "scene.yaml").string() + " --out " + (w / "r").string());
  EXPECT_EQ(r.output.find("invalid node"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace hovs
