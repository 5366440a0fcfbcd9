// The variable-scale unit's motion axes (the article's section 3.1, item 2): the turret that puts a mirror over
// the camera, the push rod that sets the mirror's height, two lateral alignment axes, the two tilts the mounting
// allows and the lens focus. One interface for every implementation: the simulated plant below (in simulated
// time), and a real motion controller (hw/) behind the same calls.
//
// Units: the turret and the tilts in radians, the rod, the lateral axes and the focus distance in metres.
// Axis meaning, in the mirror's nominal frame (conventions.h; z from the camera towards the mirror):
//   turret  rotation of the turret disc; mirror k is over the camera at its slot angle
//   rod     height of the mounting plate (the mirror's rim plane) above the camera's pinhole
//   x, y    lateral position of the plate
//   tilt_x, tilt_y  rotation of the plate about its centre, about x and y
//   focus   the lens' focus distance
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <random>
#include <string>

namespace hovs::rig {

enum class AxisId { kTurret = 0, kRod, kX, kY, kTiltX, kTiltY, kFocus };
inline constexpr int kAxisCount = 7;
const char* AxisName(AxisId axis);
inline AxisId AxisAt(int i) { return static_cast<AxisId>(i); }
// The turret and the tilts are angles (radians in code, degrees in machine files); the others lengths (m).
bool AxisIsAngular(AxisId axis);
// A position or length of the axis as the machine file gives it: "12.5 deg" or "0.0032 m".
std::string AxisValueText(AxisId axis, double value);

// What a real or simulated axis is like. The simulated plant uses every field; a real controller reports its
// travel and step and leaves the rest to the hardware.
struct AxisSpec {
  double min = 0, max = 0;      // travel
  double step = 1e-6;           // one motor step: commands are quantised to it
  double time_constant = 0.05;  // s, first-order lag of the motor towards its commanded position
  double backlash = 0;          // dead band between the motor and the output, full width
  double noise = 0;             // 1 sigma, added to the output at the end of every move (repeatability)
  // `axis` gives the unit of the values in errors (the machine file's: degrees for the angular axes).
  void Check(const std::string& where, AxisId axis) const;
};

// Injectable faults of the simulated plant.
struct AxisFault {
  bool stuck = false;       // the output never moves (a seized bearing, a broken coupling)
  double lost_steps = 0.0;  // fraction of every move the motor misses while reporting it done, in [0, 1)
};

// One axis of a motion controller. Positions are absolute, in the axis' unit.
class Axis {
 public:
  virtual ~Axis() = default;
  virtual AxisId id() const = 0;
  virtual const AxisSpec& spec() const = 0;
  // Starts a move to `target` (quantised to the step). Throws hovs::Error naming the axis when the target lies
  // outside the travel or the controller refuses it.
  virtual void MoveTo(double target) = 0;
  // Where the controller believes the axis is (its step count): open-loop hardware knows nothing better.
  virtual double Reported() const = 0;
  virtual bool Moving() const = 0;
};

// All axes of one unit and its clock.
class Machine {
 public:
  virtual ~Machine() = default;
  virtual Axis& axis(AxisId id) = 0;
  virtual double Now() const = 0;  // s
  // Waits until no axis moves; throws hovs::Error naming the axes still moving after timeout_s.
  virtual void WaitIdle(double timeout_s) = 0;
};

// The simulated plant of one axis: the motor follows the quantised command with a first-order lag; the output
// follows the motor through a dead band of `backlash`; each completed move leaves the output off by N(0, noise).
class SimulatedAxis final : public Axis {
 public:
  SimulatedAxis(AxisId id, const AxisSpec& spec, double start, uint64_t seed);
  AxisId id() const override { return id_; }
  const AxisSpec& spec() const override { return spec_; }
  void MoveTo(double target) override;
  double Reported() const override { return commanded_; }
  bool Moving() const override { return moving_; }

  void Advance(double dt);                             // simulated time
  double Output() const { return output_ + offset_; }  // the true position (ground truth)
  void SetFault(const AxisFault& fault) { fault_ = fault; }
  const AxisFault& fault() const { return fault_; }

 private:
  AxisId id_;
  AxisSpec spec_;
  double commanded_ = 0;                        // quantised command (what the controller reports)
  double goal_ = 0;                             // where the motor really goes (less lost steps)
  double motor_ = 0, output_ = 0, offset_ = 0;  // offset_: repeatability noise of the last move
  bool moving_ = false;
  AxisFault fault_;
  std::mt19937_64 rng_;
};

// Every axis simulated, with a clock that advances in `tick` steps while waiting.
class SimulatedMachine final : public Machine {
 public:
  // start: true initial positions; seed: the noise of all axes.
  SimulatedMachine(const std::array<AxisSpec, kAxisCount>& specs, const std::array<double, kAxisCount>& start,
                   uint64_t seed, double tick = 0.002);
  Axis& axis(AxisId id) override { return *axes_[static_cast<int>(id)]; }
  SimulatedAxis& sim(AxisId id) { return *axes_[static_cast<int>(id)]; }
  const SimulatedAxis& sim(AxisId id) const { return *axes_[static_cast<int>(id)]; }
  double Now() const override { return now_; }
  void WaitIdle(double timeout_s) override;
  void Advance(double dt);
  std::array<double, kAxisCount> TruePositions() const;

 private:
  std::array<std::unique_ptr<SimulatedAxis>, kAxisCount> axes_;
  double now_ = 0, tick_;
};

}  // namespace hovs::rig
