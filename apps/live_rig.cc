// hovs live --rig R/rig.json --simulate MACHINE.yaml: the live loop on the simulated variable-scale unit, with
// switches during the stream (--switch FRAME:MIRROR). Only ready frames are expanded, each with its mirror's mapping
// from the rig folder; the frames taken while the unit moves, aligns or focuses are held and logged in live.json
// with their true pose.
#include "apps/live_rig.h"

#include <cstdio>
#include <iostream>
#include <optional>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/io.h"
#include "hw/rig_live.h"
#include "rig/rig_study.h"
#include "unwrap/remap_table.h"

namespace hovs::apps {

void AddRigLiveOptions(CLI::App* sub, RigLiveCliOptions* o) {
  sub->add_option("--rig", o->rig_json,
                  "a rig folder's rig.json (hovs rig calibrate): live on the variable-scale unit given by --simulate");
  sub->add_option("--switch", o->switches, "FRAME:MIRROR: turn to MIRROR before that frame (repeatable; with --rig)");
  sub->add_option("--start", o->start, "the mirror the unit starts on (with --rig; default: the rig folder's first)");
  AddBounded(sub, "--rig-fps", &o->fps, "frames per second of machine time (with --rig)", 0, 1000, true);
  AddBounded(sub, "--seed", &o->seed, "the machine's seats and noise (with --rig; -1: the rig folder's seed)", -1,
             9007199254740992.0);
}

namespace {

std::vector<std::pair<int64_t, int>> ParseSwitches(const std::vector<std::string>& texts, const rig::TurretSpec& spec) {
  std::vector<std::pair<int64_t, int>> out;
  for (const auto& t : texts) {
    const size_t colon = t.find(':');
    long long frame = -1;
    int end = -1;
    HOVS_REQUIRE(colon != std::string::npos && std::sscanf(t.c_str(), "%lld%n", &frame, &end) == 1 &&
                     end == static_cast<int>(colon) && frame >= 0,
                 "--switch", "expected FRAME:MIRROR with FRAME >= 0 (got '", t, "')");
    out.emplace_back(frame, spec.MirrorIndex(t.substr(colon + 1)));
  }
  return out;
}

}  // namespace

int RunRigLiveCommand(const RigLiveCliOptions& c, const RigLiveCommon& common, const GlobalOptions& global) {
  HOVS_REQUIRE(!common.machine.empty(), "--rig",
               "needs --simulate MACHINE.yaml (the unit runs in simulation; a "
               "real turret behind a GRBL controller is not driven by hovs live yet)");
  HOVS_REQUIRE(common.frames > 0, "--frames", "a rig run needs a frame count");
  HOVS_REQUIRE(common.write_every == 0 || !common.out.empty(), "--write-every", "needs --out");
  rig::TurretSpec spec = rig::LoadTurretSpec(common.machine);
  const rig::RigFolder folder = rig::LoadRigFolder(c.rig_json, spec);
  HOVS_REQUIRE(!folder.mirrors.empty(), c.rig_json, "holds no mirror");
  spec.downscale = folder.downscale;  // the frames must be the size its calibrations and maps are for
  std::map<int, unwrap::RemapTable> tables;
  for (const auto& [id, e] : folder.mirrors) tables.emplace(spec.MirrorIndex(id), unwrap::LoadRemapTable(e.map));
  hw::RigLiveOptions lo;
  lo.frames = common.frames, lo.write_every = common.write_every;
  lo.interpolation = unwrap::ParseInterpolation(common.interp);
  lo.switches = ParseSwitches(c.switches, spec);
  rig::RigStreamOptions so;
  so.fps = c.fps;
  so.start_mirror = spec.MirrorIndex(c.start.empty() ? folder.mirrors.begin()->first : c.start);
  HOVS_REQUIRE(tables.count(so.start_mirror), "--start", "mirror '", c.start, "' has no entry in ", c.rig_json);
  so.seed = c.seed >= 0 ? static_cast<uint64_t>(c.seed) : folder.seed.value_or(1);
  rig::SimulatedRigStream stream(spec, so);
  std::optional<StagedDirectory> staged;
  if (!common.out.empty())
    staged.emplace(common.out, "live", std::vector<std::filesystem::path>{folder.root, common.machine});
  lo.out_dir = staged ? staged->staging() : std::filesystem::path();
  std::atomic<bool> stop{false};
  const InterruptScope interrupt(&stop);
  const hw::RigLiveRun r = hw::RunRigLive(stream, spec, tables, lo, &stop);
  nlohmann::json j = {{"tool", "hovs live"},
                      {"versions", common.versions},
                      {"source", "--simulate " + common.machine},
                      {"rig", c.rig_json},
                      {"seed", so.seed},
                      {"fps_machine_time", so.fps},
                      {"start", spec.mirrors[so.start_mirror].id},
                      {"interpolation", common.interp},
                      {"render_seconds", stream.render_seconds()}};
  j.update(hw::RigLiveJson(spec, r, stream.switches(), lo));
  if (staged) {
    WriteFileAtomic(lo.out_dir / "live.json", j.dump(1) + "\n");
    staged->Commit();
  }
  if (global.json) {
    std::cout << j.dump(1) << "\n";
  } else if (!global.quiet) {
    std::printf(
        "hovs live: %zu frames of the unit (%.1f s machine time): %d expanded, %d held (moving, aligning, "
        "focusing, fault), %zu switches, %d mapping swaps; ready frames outside the tolerance: %d\n",
        r.frames.size(), r.frames.empty() ? 0.0 : r.frames.back().time, r.live.processed, r.held,
        stream.switches().size(), r.swaps, r.ready_outside_tolerance);
  }
  // A fault of the machine is not bad input: one error naming it, exit 1, the run's log kept.
  for (const auto& s : stream.switches())
    if (!s.failure.empty()) {
      std::cerr << "hovs live: error: the switch to mirror '" << spec.mirrors[s.to].id << "' failed: " << s.failure
                << (common.out.empty() ? "" : " (live.json written)") << "\n";
      return 1;
    }
  return 0;
}

}  // namespace hovs::apps
