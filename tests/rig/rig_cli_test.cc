// hovs rig on the command line: an alignment study's JSON against the acceptance, a fault's exit code and error
// naming the axis with the state written, bad inputs (exit 2, nothing written), and a switch that loads the new
// mirror's calibration and mapping file from a rig folder; hovs live on the unit, with a switch during the stream.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <vector>
#include <nlohmann/json.hpp>

#include "core/io.h"
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
                                "rig switch --machine " + kMachine, std::string("live --rig /nonexistent.json -n 5"),
                                "live --rig /nonexistent.json --simulate " + kMachine + " -n 5",
                                "live --switch 3:wide --simulate " + kMachine + " --model " + kMachine + " -n 5"}) {
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

TEST(RigCli, AnImpossibleMachineIsRefusedAtLoadNamingTheKey) {
  // Each of these loaded and failed later as "the label is covered" or a stuck axis (or asked OpenCV for
  // dictionary -1): the machine's geometry is checked when the file is read.
  std::ifstream in(kMachine);
  const std::string good((std::istreambuf_iterator<char>(in)), {});
  const fs::path dir = Scratch("rig", "machines");
  fs::create_directories(dir);
  int n = 0;
  const auto refused = [&](const std::string& from, const std::string& to, const std::string& needle) {
    std::string text = good;
    ASSERT_NE(text.find(from), std::string::npos) << from;
    text.replace(text.find(from), from.size(), to);
    text.replace(text.find("reference_board.yaml"), 20, std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
    const fs::path file = dir / ("m" + std::to_string(n++) + ".yaml");
    std::ofstream(file) << text;
    const fs::path out = dir / "out";
    const auto r = Hovs("rig align --machine " + file.string() + " --starts 1 --out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << to << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << to << "\n" << r.output;
    EXPECT_NE(r.output.find(file.string()), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
  };
  refused("dictionary: DICT_4X4_50", "dictionary: DICT_BOGUS", "unknown ArUco dictionary 'DICT_BOGUS'");
  refused("rim_diameter: 0.080, slot_deg: 90}", "rim_diameter: 0.080, slot_deg: 0}", "overlap");  // one slot, two
  refused("[0.043, 0.033], [-0.043, 0.033]", "[43.0, 0.033], [-0.043, 0.033]", "label.centres[0]");
  refused("x:      {min: -0.005, max: 0.005, step: 1.0e-6", "x:      {min: -0.005, max: 0.005, step: 0.009",
          "a hundredth of the travel");
  refused("tilt_x: {min: -3, max: 3, step: 0.0005", "tilt_x: {min: -3, max: 3, step: 0.01",
          "half the alignment's tolerance");
  refused("slot_deg: 270}", "slot_deg: 400}", "outside the turret's travel [-10 deg, 370 deg]");
  refused("focus:  {min: 0.08, max: 0.40", "focus:  {min: 0.30, max: 0.40", "the focus travel");
  refused("turret: {radius: 0.09}", "turret: {radius: 0.02}", "overlap");  // four plates on a 20 mm turret
  refused("camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.020}",
          "camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, lens_aperture: 0.020}",
          "missing 'camera.height'");
  // Sixteen plates on the 90 mm turret.
  std::string mirrors;
  for (int k = 0; k < 16; ++k)
    mirrors += "  - {id: m" + std::to_string(k) +
               ", a: 0.048, b: 0.044, rim_diameter: 0.080, slot_deg: " + std::to_string(22.5 * k) + "}\n";
  const size_t first = good.find("  - {id: reference"), last = good.find("label:");
  refused(good.substr(first, last - first), mirrors, "overlap");
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
  // The optics' prediction beside it: within says whether the loop's focus lies in the depth of focus.
  const auto& predicted = j["focus"]["predicted"];
  const double focus = j["focus"]["focus_m"], near = predicted["depth_of_focus_m"][0],
               far = predicted["depth_of_focus_m"][1];
  EXPECT_EQ(predicted["within"].get<bool>(), focus >= near && focus <= far) << j["focus"].dump();
  EXPECT_NEAR(focus, predicted["best_focus_m"].get<double>(), 0.010);
  EXPECT_EQ(j["loaded"]["map_views"], 6);
  EXPECT_EQ(j["fresh_board"]["corners"], 35);
  EXPECT_LT(j["fresh_board"]["rms_px"].get<double>(), 0.1);

  // The same folder at another resolution is refused before anything runs.
  const auto bad = Hovs("rig switch --machine " + kMachine + " --to reference --rig " + (rig / "rig.json").string() +
                        " --out " + Scratch("rig", "bad-switch").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("give --downscale 2"), std::string::npos) << bad.output;

  // rig.json is checked, not trusted: every variant below once switched with exit 0 (or followed the path).
  const std::string good = test::Run("cat " + (rig / "rig.json").string()).output;
  const auto variant = [&](const std::function<void(nlohmann::json*)>& edit) {
    nlohmann::json j = nlohmann::json::parse(good);
    edit(&j);
    std::ofstream(rig / "rig.json") << j.dump(1);
  };
  const auto switch_refused = [&](const std::string& needle, const std::string& machine = kMachine,
                                  const std::string& to = "reference") {
    const fs::path o = Scratch("rig", "refused-switch");
    const auto s = Hovs("rig switch --machine " + machine + " --downscale 2 --to " + to + " --rig " +
                        (rig / "rig.json").string() + " --out " + o.string());
    EXPECT_EQ(s.exit_code, 2) << needle << "\n" << s.output;
    EXPECT_NE(s.output.find(needle), std::string::npos) << s.output;
    EXPECT_FALSE(fs::exists(o));
  };
  variant([](nlohmann::json* j) { (*j)["mirrors"]["reference"]["calibration"] = "../elsewhere/calibration.json"; });
  switch_refused("leaves the file's folder");
  variant([](nlohmann::json* j) { (*j)["mirrors"]["reference"]["map"] = "/etc/passwd"; });
  switch_refused("absolute");
  // Another mirror's files under this mirror's name: the wide mirror's slot given the reference's calibration.
  variant([](nlohmann::json* j) {
    (*j)["mirrors"]["wide"] = (*j)["mirrors"]["reference"];
    (*j)["mirrors"]["wide"]["mirror"] = {{"a", 0.065}, {"b", 0.051}, {"rim_diameter", 0.080}};
  });
  switch_refused("does not image mirror 'wide''s field", kMachine, "wide");
  // A calibration changed after it was written, and a map of another size with its checksum made to match.
  std::string calibration = test::Run("cat " + (rig / "reference/calibration/calibration.json").string()).output;
  std::ofstream(rig / "reference/calibration/calibration.json") << calibration + " ";
  variant([](nlohmann::json*) {});
  switch_refused("does not match its checksum");
  std::ofstream(rig / "reference/calibration/calibration.json") << calibration;
  const fs::path small = Scratch("rig", "small");
  ASSERT_EQ(Hovs("-q dataset --kind mono_calibration --scene " + std::string(HOVS_SOURCE_DIR) +
                 "/scenes/reference_calibration.yaml --count 1 --samples 1 --downscale 10 --out " + small.string())
                .exit_code,
            0);
  ASSERT_EQ(Hovs("-q unwrap --model " + (small / "dataset.json").string() + " --layout article --input " +
                 (small / "dataset.json").string() + " --save-map " + (rig / "other.hmap").string() + " --out " +
                 (small / "views").string())
                .exit_code,
            0);
  variant([&](nlohmann::json* j) { (*j)["mirrors"]["reference"]["map"] = "other.hmap"; });
  switch_refused("does not match its checksum");
  variant([&](nlohmann::json* j) {
    (*j)["mirrors"]["reference"]["map"] = "other.hmap";
    (*j)["mirrors"]["reference"]["map_checksum"] = FileChecksum(rig / "other.hmap");
  });
  switch_refused("maps 275 x 220 images; the folder's are 1375 x 1100");
  // A folder made on another machine (a label of other markers).
  std::ifstream in(kMachine);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  text.replace(text.find("margin: 0.001"), 13, "margin: 0.0012");
  text.replace(text.find("reference_board.yaml"), 20, std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
  const fs::path other_machine = Scratch("rig", "other-machine.yaml");
  std::ofstream(other_machine) << text;
  variant([](nlohmann::json*) {});
  switch_refused("was made on machine", other_machine.string());
  std::ofstream(rig / "rig.json") << good;
}

TEST(RigCli, LiveHoldsEveryFrameTakenWhileTheUnitIsNotReady) {
  // Two mirrors calibrated at half resolution; then a live stream that brings the unit up on the wide mirror and
  // switches to the reference mirror during the stream. Every frame is either expanded with the mapping of the
  // mirror it shows or held; no expanded frame's true pose misses the acceptance.
  const fs::path rig = Scratch("rig", "live-folder");
  const auto c = Hovs("rig calibrate --machine " + kMachine +
                      " --downscale 2 --mirror wide --mirror reference --frames 5 "
                      "--seed 5 --out " +
                      rig.string());
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const fs::path out = Scratch("rig", "live");
  constexpr int kFrames = 100, kSwitchAt = 40;
  const auto r = Hovs("live --rig " + (rig / "rig.json").string() + " --simulate " + kMachine +
                      " --start wide --switch " + std::to_string(kSwitchAt) + ":reference --rig-fps 2 -n " +
                      std::to_string(kFrames) + " --write-every 3 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = ReadJson(out / "live.json");
  EXPECT_EQ(j["seed"], 5);  // the rig folder's seats
  ASSERT_EQ(j["frames"].size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(j["frames_expanded"].get<int>() + j["frames_held"].get<int>(), kFrames);
  EXPECT_EQ(j["ready_outside_tolerance"], 0);
  EXPECT_EQ(j["mapping_swaps"], 1);
  ASSERT_EQ(j["switches"].size(), 2u);  // the bring-up on wide, then the switch
  for (const auto& s : j["switches"]) EXPECT_TRUE(s["converged"].get<bool>()) << s.dump();
  EXPECT_EQ(j["switches"][1]["from"], "wide");
  EXPECT_EQ(j["switches"][1]["to"], "reference");
  for (const char* state : {"moving", "aligning", "focusing"})
    EXPECT_GT(j["held_by_state"].value(state, 0), 0) << state;
  const int64_t switch_first = j["switches"][1]["frames"][0], switch_last = j["switches"][1]["frames"][1];
  EXPECT_EQ(switch_first, kSwitchAt);
  ASSERT_LT(switch_last + 1, kFrames) << "the switch must end within the run";
  int written = 0, expanded_after = 0;
  for (const auto& f : j["frames"]) {
    const int64_t i = f["index"];
    const bool expanded = f["expanded"];
    // Held exactly while a switch runs, expanded otherwise, with the mapping of the mirror the unit is on.
    const bool in_switch = i <= j["switches"][0]["frames"][1].get<int64_t>() || (i >= switch_first && i <= switch_last);
    EXPECT_EQ(expanded, !in_switch) << f.dump();
    EXPECT_EQ(f["state"] == "ready", expanded) << f.dump();
    if (expanded) {
      EXPECT_TRUE(f["within_tolerance"].get<bool>()) << f.dump();
      EXPECT_EQ(f["mirror"], i > switch_last ? "reference" : "wide") << f.dump();
      expanded_after += i > switch_last;
    }
    if (f["state"] == "moving") { EXPECT_FALSE(expanded); }
    if (f["written"].get<bool>()) {
      ++written;
      const std::string stem = "frame" + std::string(6 - std::to_string(i).size(), '0') + std::to_string(i) + "_" +
                               f["mirror"].get<std::string>();
      EXPECT_TRUE(fs::exists(out / (stem + "_view0.png"))) << stem;
    }
  }
  EXPECT_GT(expanded_after, 0);
  EXPECT_EQ(written, j["frames_written"].get<int>());
  EXPECT_GT(written, 0);
}

}  // namespace
}  // namespace hovs
