// hovs rig on the command line: an alignment study's JSON against the acceptance, a fault's exit code and error
// naming the axis with the state written, bad inputs (exit 2, nothing written), and a switch that loads the new
// mirror's calibration and mapping file from a rig folder.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <vector>
#include <nlohmann/json.hpp>

#include "tests/cli_helper.h"

namespace hovs {
namespace {

namespace fs = std::filesystem;
using test::Hovs;
using test::Scratch;

const std::string kMachine = std::string(HOVS_SOURCE_DIR) + "/scenes/turret.yaml";

nlohmann::json ReadJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

TEST(RigCli, AlignStudyMeetsTheAcceptanceOnTwoMirrors) {
  const fs::path out = Scratch("rig", "align");
  const auto r = Hovs("rig align --machine " + kMachine +
                      " --mirror wide --mirror near-ground --starts 2 --seed 4 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = ReadJson(out / "align.json");
  ASSERT_EQ(j["runs"].size(), 4u);
  for (const auto& run : j["runs"]) {
    EXPECT_TRUE(run["converged"].get<bool>());
    EXPECT_NEAR(run["start"]["lateral_mm"].get<double>(), 2.0, 0.05);
    EXPECT_LT(run["final_truth"]["lateral_mm"].get<double>(), 0.05);
    EXPECT_LT(run["final_truth"]["tilt_deg"].get<double>(), 0.02);
    EXPECT_LT(std::abs(run["final_truth"]["height_mm"].get<double>()), 0.05);
    EXPECT_LE(run["steps"].size(), 30u);
    // Every step logs the state, the measurement, the command and the machine time.
    for (const char* k : {"truth", "measured", "reported", "command", "time_s"})
      EXPECT_TRUE(run["steps"][0].contains(k));
  }
  EXPECT_TRUE(j.contains("versions"));
}

TEST(RigCli, AStuckAxisExitsOneNamingItWithTheStateWritten) {
  const fs::path out = Scratch("rig", "stuck");
  const auto r = Hovs("rig align --machine " + kMachine + " --mirror reference --starts 1 --fault tilt_x:stuck --out " +
                      out.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("axis tilt_x does not move"), std::string::npos) << r.output;
  const auto j = ReadJson(out / "align.json");
  EXPECT_EQ(j["runs"][0]["failing"], "tilt_x");
  EXPECT_LE(j["runs"][0]["steps"].size(), 6u);
}

TEST(RigCli, BadInputsExitTwoAndWriteNothing) {
  const fs::path out = Scratch("rig", "bad");
  for (const std::string& args :
       std::vector<std::string>{"rig align --machine " + kMachine + " --fault wheel:stuck",
                                "rig align --machine " + kMachine + " --mirror fisheye",
                                std::string("rig align --machine /nonexistent.yaml"),
                                "rig switch --machine " + kMachine + " --to reference --rig /nonexistent.json",
                                "rig switch --machine " + kMachine}) {
    const auto r = Hovs(args + " --out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
  // A machine file with a mirror the rod cannot reach.
  const fs::path bad = Scratch("rig", "machine.yaml");
  std::ifstream in(kMachine);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto swap = [&](const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
  };
  swap("rod:    {min: 0.110, max: 0.170", "rod:    {min: 0.110, max: 0.140");
  swap("reference_board.yaml", std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
  std::ofstream(bad) << text;
  const auto r = Hovs("rig align --machine " + bad.string() + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("mirror 'wide' needs the plate at"), std::string::npos) << r.output;
}

TEST(RigCli, ACalibrationStoredInTheRigFolderHoldsAfterASwitch) {
  // The reference mirror calibrated where the loop put it (at half resolution), then a switch from the wide
  // mirror back to it: align, focus, load its files, and a fresh board through the stored model.
  const fs::path rig = Scratch("rig", "folder");
  const auto c = Hovs("rig calibrate --machine " + kMachine +
                      " --downscale 2 --mirror reference --frames 5 --seed 3 --out " + rig.string());
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_TRUE(fs::exists(rig / "reference" / "views.hmap"));
  const auto record = ReadJson(rig / "rig.json");
  EXPECT_EQ(record["downscale"], 2);
  EXPECT_LT(record["mirrors"]["reference"]["rms_px"].get<double>(), 0.15);

  const fs::path out = Scratch("rig", "switch");
  const auto r = Hovs("rig switch --machine " + kMachine + " --downscale 2 --seed 3 --from wide --to reference --rig " +
                      (rig / "rig.json").string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = ReadJson(out / "switch.json");
  EXPECT_EQ(j["from"], "wide");
  EXPECT_EQ(j["to"], "reference");
  EXPECT_TRUE(j["converged"].get<bool>());
  EXPECT_GT(j["move_seconds"].get<double>(), 0.5);  // the turret turns 90 deg
  EXPECT_LT(j["final_truth"]["lateral_mm"].get<double>(), 0.05);
  EXPECT_LT(j["final_truth"]["tilt_deg"].get<double>(), 0.02);
  EXPECT_GT(j["focus"]["focus_m"].get<double>(), 0.14);  // the reference mirror's image lies beyond its plate
  EXPECT_EQ(j["loaded"]["map_views"], 6);
  EXPECT_EQ(j["fresh_board"]["corners"], 35);
  EXPECT_LT(j["fresh_board"]["rms_px"].get<double>(), 0.1);

  // The same folder at another resolution is refused before anything runs.
  const auto bad = Hovs("rig switch --machine " + kMachine + " --to reference --rig " + (rig / "rig.json").string() +
                        " --out " + Scratch("rig", "bad-switch").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("give --downscale 2"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace hovs
