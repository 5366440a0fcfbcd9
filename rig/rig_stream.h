// The variable-scale unit streaming: a simulated camera that delivers frames at a fixed rate of machine time while
// the unit runs, with switches carried out by the loop on the stream's own frames (the measurements and the focus
// sweep are frames of the stream). Every frame says what the unit was doing when it was taken: ready (aligned and
// focused on a known mirror: its views can be trusted) or held (moving, aligning, focusing, or stopped by a fault),
// and carries the ground truth of the mirror's pose, so a live loop can be checked frame by frame.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rig/focus.h"
#include "rig/positioning.h"
#include "rig/turret.h"

namespace hovs::rig {

enum class UnitState { kReady, kMoving, kAligning, kFocusing, kFault };
const char* UnitStateName(UnitState state);

// The acceptance's alignment: a ready frame's true pose must be within these (m, rad, m).
struct AlignmentTolerance {
  double lateral = 0.05e-3, tilt = 0.02 * M_PI / 180, height = 0.05e-3;
  bool Holds(const MirrorPose& pose) const;
};

struct StreamedFrame {
  int64_t index = 0;
  double time = 0;  // machine time of the exposure, s
  int mirror = 0;   // the mirror the unit is on (or going to, while it switches)
  UnitState state = UnitState::kReady;
  std::optional<TurretImage> image;  // rendered when the frame is used: ready, or a measurement / focus image
  MirrorPose truth;                  // the mirror's true pose at the exposure
  bool Ready() const { return state == UnitState::kReady; }
};

struct SwitchRecord {
  int from = 0, to = 0;
  int64_t first_frame = 0, last_frame = 0;  // the frames the switch held
  double start_time = 0, end_time = 0;      // machine time, s
  AlignResult align;
  std::optional<FocusResult> focus;
  std::string failure;  // empty when the unit ended ready on `to`
};

struct RigStreamOptions {
  double fps = 10;       // frames per second of machine time
  int start_mirror = 0;  // the unit starts on it (axes at its nominal positions, the lens on the plate) and is
                         // brought up (aligned, focused) before its first ready frame
  uint64_t seed = 1;     // the seats (as hovs rig calibrate --seed), the axes' noise, the renders
  AlignOptions align;
  FocusOptions focus;
  void Check(const std::string& where, const TurretSpec& spec) const;
};

class SimulatedRigStream {
 public:
  SimulatedRigStream(const TurretSpec& spec, const RigStreamOptions& options);
  ~SimulatedRigStream();
  // Turns to mirror k from the next frame on: the turret and rod move, the loop aligns, the lens is focused.
  void RequestSwitch(int k);
  // The next frame. While a switch runs, its frames come out in order, each with the state it was taken in.
  StreamedFrame Next();
  const std::vector<SwitchRecord>& switches() const { return switches_; }
  double render_seconds() const;
  // Faults to inject (the alignment study's): an axis that fails, a label covered from now on.
  void SetAxisFault(AxisId axis, const AxisFault& fault);
  void CoverLabel(bool covered);

 private:
  class Plant;
  void RunSwitch(int to);
  const TurretSpec& spec_;
  RigStreamOptions options_;
  std::unique_ptr<Plant> plant_;
  std::deque<StreamedFrame> queue_;
  std::optional<int> pending_;
  std::vector<SwitchRecord> switches_;
  bool fault_ = false;
};

}  // namespace hovs::rig
