// The variable-scale stage of hovs validate (apps/validation.h): every turret mirror calibrated where the loop put
// it, a round of switches each checked on a fresh board, and the same round in one live stream.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/validation.h"
#include "core/json.h"

namespace hovs::apps {
namespace fs = std::filesystem;
using json = nlohmann::json;
void VariableScale(Validation& v, uint64_t seed_value) {
  const Preset& p = v.preset();
  const fs::path& out = v.out();
  const std::string machine = v.Src("scenes/turret.yaml"), seed = std::to_string(seed_value);
  const std::string ds = std::to_string(p.downscale), rig_json = v.Out("rig/rig.json");
  // The turret's round: each mirror once, each switch from the previous one.
  const std::vector<std::string> order = {"reference", "wide", "long-range", "near-ground"};
  std::vector<std::vector<std::string>> commands = {{"rig", "calibrate", "--machine", machine, "--downscale", ds,
                                                     "--frames", std::to_string(p.rig_frames), "--seed", seed, "--out",
                                                     v.Out("rig")}};
  for (size_t k = 0; k < order.size(); ++k)
    commands.push_back({"rig", "switch", "--machine", machine, "--downscale", ds, "--seed", seed, "--from",
                        order[(k + order.size() - 1) % order.size()], "--to", order[k], "--rig", rig_json, "--out",
                        v.Out("rig-switch/to-" + order[k])});
  // The same round in one live stream at 1 frame per second of machine time: brought up on the last mirror, then a
  // switch every 50 frames (a switch holds 30-40: the move, the loop's images, the 24 images of the focus sweep).
  std::vector<std::string> live = {"live",    "--rig",         rig_json,    "--simulate", machine,
                                   "--start", order.back(),    "--rig-fps", "1",          "-n",
                                   "240",     "--write-every", "10",        "--out",      v.Out("rig-live")};
  for (size_t k = 0; k < order.size(); ++k) {
    live.push_back("--switch");
    live.push_back(std::to_string(40 + 50 * k) + ":" + order[k]);
  }
  commands.push_back(live);
  v.Stage("variable-scale unit: calibrate each mirror, switch round, live", commands, [&]() {
    json switches = json::array();
    double worst_board = 0, worst_lateral = 0, worst_tilt = 0, worst_height = 0;
    int focus_outside = 0;  // switches whose focus loop ended outside the optics' depth of focus (rig/focus.h)
    for (const auto& id : order) {
      const json j = ReadJsonFile(out / "rig-switch" / ("to-" + id) / "switch.json");
      worst_board = std::max(worst_board, Num(j, {"fresh_board", "rms_px"}));
      worst_lateral = std::max(worst_lateral, Num(j, {"final_truth", "lateral_mm"}));
      worst_tilt = std::max(worst_tilt, Num(j, {"final_truth", "tilt_deg"}));
      worst_height = std::max(worst_height, std::abs(Num(j, {"final_truth", "height_mm"})));
      const json* predicted = j.contains("focus") ? &j["focus"]["predicted"] : nullptr;
      focus_outside += !(predicted && predicted->is_object() && (*predicted)["within"].get<bool>());
      switches.push_back({{"from", j["from"]},
                          {"to", id},
                          {"converged", j["converged"]},
                          {"fresh_board_rms_px", Num(j, {"fresh_board", "rms_px"})},
                          {"final_truth", j["final_truth"]},
                          {"focus", j.contains("focus") ? json{{"focus_m", j["focus"]["focus_m"]},
                                                               {"predicted", j["focus"].value("predicted", json())}}
                                                        : json(nullptr)},
                          {"images", j["images"]}});
    }
    const json l = ReadJsonFile(out / "rig-live" / "live.json");
    int live_failures = 0;
    for (const auto& s : l["switches"]) live_failures += !s["failure"].get<std::string>().empty();
    v.Figure("variable_scale", {{"switches", switches},
                                {"live",
                                 {{"frames", l["frames_streamed"]},
                                  {"expanded", l["frames_expanded"]},
                                  {"held_by_state", l["held_by_state"]},
                                  {"ready_outside_tolerance", l["ready_outside_tolerance"]},
                                  {"mapping_swaps", l["mapping_swaps"]}}}});
    // The variable-scale acceptance, measured against the renderer's truth.
    v.Check("variable scale: worst fresh-board RMS after a switch", worst_board, "max", p.rig_board_rms_px, "px",
            "variable-scale acceptance");
    v.Check("variable scale: worst lateral offset after a switch", worst_lateral, "max", p.rig_offset_mm, "mm",
            "variable-scale acceptance");
    v.Check("variable scale: worst tilt after a switch", worst_tilt, "max", p.rig_tilt_deg, "deg",
            "variable-scale acceptance");
    v.Check("variable scale: worst height error after a switch", worst_height, "max", p.rig_offset_mm, "mm",
            "variable-scale acceptance");
    v.Check("variable scale: switches whose focus loop ended outside the predicted depth of focus", focus_outside,
            "max", 0, "", "optics/README.md (depth of focus)", /*gate=*/false);
    v.Check("variable scale: live switches that failed", live_failures, "max", 0, "", "variable-scale acceptance");
    v.Check("variable scale: live mapping swaps", Num(l, {"mapping_swaps"}), "min", 4, "", "variable-scale acceptance");
    v.Check("variable scale: live frames expanded outside the tolerance", Num(l, {"ready_outside_tolerance"}), "max", 0,
            "frames", "variable-scale acceptance");
  });
}

}  // namespace hovs::apps
