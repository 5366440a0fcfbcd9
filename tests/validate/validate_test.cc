// hovs validate, reduced preset: the whole chain (renders -> detection -> calibration of both units -> stereo
// calibration -> views -> depth -> the real VMR images) end to end. Every gate of the run must pass, every
// target must have been measured, and a run stopped by bad input leaves valid partial results naming the stage.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

TEST(Validate, ReducedPresetPassesEveryGateEndToEnd) {
  const fs::path out = test::Scratch("validate", "reduced");
  const auto r = test::Hovs("validate --preset reduced --source " + std::string(HOVS_SOURCE_DIR) + " --real " +
                            std::string(HOVS_SHARED_DIR) + "/data/vmr --out " + out.string());
  std::printf(
      "%s\n",
      r.output.substr(r.output.find("hovs validate (") == std::string::npos ? 0 : r.output.find("hovs validate ("))
          .c_str());
  EXPECT_EQ(r.exit_code, 0);
  const auto m = nlohmann::json::parse(ReadFile(out / "metrics.json"));
  EXPECT_EQ(m["config"]["preset"], "reduced");
  EXPECT_TRUE(m.contains("versions"));
  ASSERT_GE(m["checks"].size(), 14u);
  int gates = 0;
  for (const auto& c : m["checks"]) {
    ASSERT_FALSE(c["value"].is_null()) << c.dump() << ": every check must have been measured";
    if (!c["gate"].get<bool>()) continue;
    ++gates;
    EXPECT_TRUE(c["pass"].get<bool>()) << c.dump();
  }
  EXPECT_GE(gates, 9);
  int done = 0;
  for (const auto& s : m["stages"]) done += s["status"] == "done";
  EXPECT_GE(done, 8);
  EXPECT_TRUE(fs::exists(out / "report.html"));
  EXPECT_TRUE(fs::exists(out / "depth" / "error_map.png"));
  EXPECT_TRUE(fs::exists(out / "calib-left" / "calib_results.txt"));
  EXPECT_TRUE(fs::exists(out / "calib-left" / "figures" / "left_0000.png"));  // detection + reprojection plot
  // The variable-scale stage: four switches, each checked on a fresh board, and the live round.
  const auto& vs = m["figures"]["variable_scale"];
  ASSERT_EQ(vs["switches"].size(), 4u) << vs.dump();
  EXPECT_EQ(vs["live"]["mapping_swaps"], 4);
  EXPECT_EQ(vs["live"]["ready_outside_tolerance"], 0);
  EXPECT_TRUE(fs::exists(out / "rig-live" / "live.json"));
  fs::remove_all(out.parent_path());
}

TEST(Validate, BadInputStopsTheRunNamingTheStageAndLeavesTheEarlierReportAlone) {
  const fs::path dir = test::Scratch("validate", "bad");
  // A source tree whose street scene is broken: the render stage fails after the calibration sets are written.
  fs::create_directories(dir / "src" / "scenes");
  fs::create_directories(dir / "src" / "design");
  fs::copy_file(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml",
                dir / "src/scenes/reference_stereo.yaml");
  fs::copy_file(std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml", dir / "src/design/reference.yaml");
  fs::copy_file(std::string(HOVS_SOURCE_DIR) + "/scenes/turret.yaml", dir / "src/scenes/turret.yaml");
  WriteFileAtomic(dir / "src/scenes/street.yaml", "name: street\nunits: 12\n");
  // An earlier report of hovs validate in the output folder.
  fs::create_directories(dir / "run");
  WriteFileAtomic(dir / "run" / kOutputMarker, "{\"format\": \"hovs-output\", \"command\": \"validate\"}\n");
  WriteFileAtomic(dir / "run" / "report.html", "the earlier report");
  const auto r = test::Hovs("validate --preset reduced --source " + (dir / "src").string() + " --real '' --out " +
                            (dir / "run").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("validate stage 'render"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("street.yaml"), std::string::npos) << r.output;
  // The failed run is staged like every report: the earlier one is byte for byte as it was, nothing is left over.
  EXPECT_EQ(ReadFile(dir / "run" / "report.html"), "the earlier report");
  EXPECT_FALSE(fs::exists(dir / "run" / "metrics.json"));
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_TRUE(e.path().filename() == "run" || e.path().filename() == "src") << e.path();
  const auto bad = test::Hovs("validate --preset tiny --out " + (dir / "x").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("unknown preset 'tiny'"), std::string::npos) << bad.output;
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace hovs
