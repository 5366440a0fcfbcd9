// The live loop on a variable-scale unit: frames of the unit's stream expanded into the views of the mirror it is
// on, with switches requested during the stream. Only a ready frame (the unit aligned and focused on a mirror whose
// mapping is loaded) is expanded, with that mirror's mapping; a frame taken while the turret, rod or focus moves,
// while the loop aligns or focuses, or after a fault is held: counted and logged with its state, never written as
// a good view. Each frame's true pose is kept so a run can be checked against the acceptance frame by frame.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "hw/live.h"
#include "rig/rig_stream.h"
#include "unwrap/remap.h"
#include "unwrap/remap_table.h"

namespace hovs::hw {

struct RigLiveOptions {
  int frames = 100;     // frames of the stream, ready and held
  int write_every = 0;  // write the views of every Nth ready frame into out_dir (0: never)
  std::filesystem::path out_dir;
  unwrap::Interpolation interpolation = unwrap::Interpolation::kBilinear;
  std::vector<std::pair<int64_t, int>> switches;  // (frame index, mirror): the switch is requested before that frame
  rig::AlignmentTolerance tolerance;              // what a ready frame's true pose is checked against
};

struct RigLiveFrame {
  int64_t index = 0;
  double time = 0;  // machine time, s
  int mirror = 0;
  rig::UnitState state = rig::UnitState::kReady;
  bool expanded = false, written = false;
  rig::MirrorPose truth;
  bool within_tolerance = false;  // the true pose against options.tolerance
};

struct RigLiveRun {
  LiveRun live;  // processed: ready frames expanded; the latencies are theirs
  std::vector<RigLiveFrame> frames;
  int held = 0;                     // frames not expanded (any state but ready)
  int ready_outside_tolerance = 0;  // ready frames whose true pose misses the tolerance (0 when the flags are right)
  int held_within_tolerance = 0;    // held frames whose true pose met it (the price of holding)
  int swaps = 0;                    // changes of the mapping in use
};

// Streams `options.frames` frames (or until *stop), requesting the scheduled switches. tables: the mapping of each
// mirror (index into the machine's mirrors); a ready frame on a mirror without one is an error naming it.
RigLiveRun RunRigLive(rig::SimulatedRigStream& stream, const rig::TurretSpec& spec,
                      const std::map<int, unwrap::RemapTable>& tables, const RigLiveOptions& options,
                      std::atomic<bool>* stop,
                      const std::function<void(const std::vector<unwrap::Image8>&)>& display = {});

// The run as live.json's body: counts (streamed, expanded, held by state, ready outside the tolerance), the
// switches (frames held, machine time, loop iterations, images, final true pose, focus), the latencies of the ready
// frames and every frame's log (state, mirror, true lateral / tilt / height).
nlohmann::json RigLiveJson(const rig::TurretSpec& spec, const RigLiveRun& run,
                           const std::vector<rig::SwitchRecord>& switches, const RigLiveOptions& options);

}  // namespace hovs::hw
