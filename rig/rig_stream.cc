#include "rig/rig_stream.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace hovs::rig {

const char* UnitStateName(UnitState state) {
  switch (state) {
    case UnitState::kReady: return "ready";
    case UnitState::kMoving: return "moving";
    case UnitState::kAligning: return "aligning";
    case UnitState::kFocusing: return "focusing";
    case UnitState::kFault: return "fault";
  }
  return "?";
}

bool AlignmentTolerance::Holds(const MirrorPose& pose) const {
  return pose.LateralM() <= lateral && pose.TiltRad() <= tilt && std::abs(pose.offset.z()) <= height;
}

void RigStreamOptions::Check(const std::string& where, const TurretSpec& spec) const {
  HOVS_REQUIRE(std::isfinite(fps) && fps > 0 && fps <= 1000, where, "the frame rate must be in (0, 1000] fps");
  HOVS_REQUIRE(start_mirror >= 0 && start_mirror < static_cast<int>(spec.mirrors.size()), where,
               "no such start mirror");
  align.Check(where + " (alignment)");
  focus.Check(where + " (focus)");
}

// The unit seen through the stream: the loop's Plant and Machine at once, so that the alignment and focus loops
// run unchanged while every frame boundary the machine's clock crosses becomes a frame of the stream. A wait for
// the axes emits the frames taken meanwhile (moving while any axis moves); an observation is the next frame,
// rendered and handed both to the loop and to the stream.
class SimulatedRigStream::Plant final : public rig::Plant, public Machine {
 public:
  Plant(const TurretSpec& spec, const RigStreamOptions& o, std::deque<StreamedFrame>* out)
      : unit_(spec, o.start_mirror, spec.NominalAxes(o.start_mirror, spec.mirrors[o.start_mirror].PlateHeight()),
              DrawSeats(spec, o.seed * 31u + 17u), o.seed),
        period_(1.0 / o.fps),
        out_(out) {}

  // rig::Plant
  Machine& machine() override { return *this; }
  TurretImage Observe() override { return Emit(true, state).image.value(); }
  std::optional<MirrorPose> Truth() const override { return unit_.Truth(); }
  int Mirror() const override { return unit_.Mirror(); }
  // Machine
  Axis& axis(AxisId id) override { return unit_.sim().axis(id); }
  double Now() const override { return unit_.sim().Now(); }
  void WaitIdle(double timeout_s) override {
    const double end = Now() + timeout_s;
    // In the machine's own ticks, stopping as soon as it is idle; a frame boundary reached meanwhile is a frame.
    while (AnyMoving() && Now() < end) {
      unit_.sim().Advance(std::min({kTick, NextFrameTime() - Now(), end - Now()}));
      if (Now() >= NextFrameTime() - 1e-12) Emit(false, state);
    }
    unit_.sim().WaitIdle(0.0);  // throws naming the axes still moving
  }

  // Advances to the next frame boundary and emits that frame (rendered when `render`).
  StreamedFrame& Emit(bool render, UnitState s) {
    while (Now() < NextFrameTime() - 1e-12) unit_.sim().Advance(std::min(kTick, NextFrameTime() - Now()));
    StreamedFrame& f = out_->emplace_back();
    f.index = next_index_++;
    f.time = Now();
    f.mirror = unit_.Mirror();
    f.state = AnyMoving() ? UnitState::kMoving : s;
    f.truth = *unit_.Truth();
    if (render) f.image.emplace(unit_.Observe());
    return f;
  }

  SimulatedUnit& unit() { return unit_; }
  int64_t next_index() const { return next_index_; }
  UnitState state = UnitState::kAligning;  // what the frames taken while the axes stand still show

 private:
  static constexpr double kTick = 0.002;  // s, the simulated machine's step
  double NextFrameTime() const { return next_index_ * period_; }
  bool AnyMoving() const {
    for (int a = 0; a < kAxisCount; ++a)
      if (unit_.sim().sim(AxisAt(a)).Moving()) return true;
    return false;
  }
  SimulatedUnit unit_;
  double period_;
  int64_t next_index_ = 0;
  std::deque<StreamedFrame>* out_;
};

SimulatedRigStream::SimulatedRigStream(const TurretSpec& spec, const RigStreamOptions& options)
    : spec_(spec), options_(options) {
  options_.Check("rig stream", spec);
  plant_ = std::make_unique<Plant>(spec, options_, &queue_);
  pending_ = options_.start_mirror;  // the bring-up
}

SimulatedRigStream::~SimulatedRigStream() = default;

void SimulatedRigStream::RequestSwitch(int k) {
  HOVS_REQUIRE(k >= 0 && k < static_cast<int>(spec_.mirrors.size()), "rig stream", "no such mirror: ", k);
  pending_ = k;
}

double SimulatedRigStream::render_seconds() const { return plant_->unit().render_seconds(); }

void SimulatedRigStream::SetAxisFault(AxisId axis, const AxisFault& fault) {
  plant_->unit().sim().sim(axis).SetFault(fault);
}

void SimulatedRigStream::CoverLabel(bool covered) { plant_->unit().CoverLabel(covered); }

void SimulatedRigStream::RunSwitch(int to) {
  Plant& p = *plant_;
  SwitchRecord rec;
  rec.from = p.Mirror(), rec.to = to;
  rec.first_frame = p.next_index();
  rec.start_time = p.Now();
  // The turret to the new slot, the rod to its plate height, the other axes home, the lens on the plate (the label
  // sharp for the loop); the frames taken meanwhile are held as moving.
  const auto target = spec_.NominalAxes(to, spec_.mirrors[to].PlateHeight());
  p.state = UnitState::kMoving;
  try {
    for (int a = 0; a < kAxisCount; ++a) p.axis(AxisAt(a)).MoveTo(target[a]);
    p.WaitIdle(120.0);
    p.unit().SetMirror(to);
    p.state = UnitState::kAligning;
    rec.align = Align(p, spec_, options_.align);
    if (rec.align.converged) {
      p.state = UnitState::kFocusing;
      rec.focus = FocusLens(p, spec_, options_.focus);
    } else {
      rec.failure = rec.align.failure;
    }
  } catch (const Error& e) { rec.failure = e.what(); }
  fault_ = !rec.failure.empty();
  p.state = fault_ ? UnitState::kFault : UnitState::kReady;
  rec.last_frame = p.next_index() - 1;
  rec.end_time = p.Now();
  switches_.push_back(std::move(rec));
}

StreamedFrame SimulatedRigStream::Next() {
  if (queue_.empty() && pending_) {
    const int to = *pending_;
    pending_.reset();
    RunSwitch(to);
  }
  // A ready unit's frame is rendered (its views are wanted); a faulted unit's is only counted.
  if (queue_.empty()) plant_->Emit(!fault_, plant_->state);
  StreamedFrame f;
  std::swap(f, queue_.front());
  queue_.pop_front();
  return f;
}

}  // namespace hovs::rig
