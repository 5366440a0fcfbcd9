// The visual positioning loop of the variable-scale unit: image, measure the plate's pose from its label, act on
// the axes, image again, until the mirror axis lies on the optical axis and the pinhole at the mirror's second
// focus; and the focus loop that maximises the mirror image's sharpness through the lens focus.
//
// Control: one PID per axis (x, y, rod, tilt_x, tilt_y) on the measured deviation e, in the axis' own unit, in
// positional form about the command u0 the loop started from: u = u0 - (kp e + ki sum(e) + kd de). The axis
// holds its position and the label measures an absolute deviation, so the plant is static, e_n = e_0 + (u_n - u0),
// and the closed loop's poles are the roots of z^2 - (1 - kp - ki) z - kp = 0: kp = 0, ki = 1 (the default) puts
// both at 0, one move cancels the deviation (dead-beat) and what backlash, noise and lost motion leave is taken
// up by the next; ki < 1 damps the response to measurement noise at one iteration more per decade. A PID tuned
// for a dynamic plant (kp = 0.9, ki = 0.15) has a pole at 0.83 here and needs about 27 iterations from 3 mm. The
// command is limited to the travel; while it saturates the error is not integrated (anti-windup).
//
// Faults end the loop with one error naming the axis or the measurement, never an endless loop:
//   stuck axis    the axis was commanded at least 5 tolerances, and 6 times the noise of the measured motion,
//                 over the last moves, and the measurement did not follow (less than 20 % of it)
//   lost steps    over two moves of at least 10 tolerances (and 15 times the noise of one measured move), the
//                 measured motion was under 80 % of the commanded
// The noise is the label's own (twice the median PnP sigma of its measurements; RequireLabelPrecision), so that
// a healthy axis at a coarse resolution is not taken for a faulty one.
//   label         the label could not be measured in three images in a row
//   not converged max_iterations reached
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rig/actuators.h"
#include "rig/label_pose.h"
#include "rig/turret.h"

namespace hovs::rig {

// What the loop acts on and observes. The simulation renders the machine's true state; real hardware grabs a
// frame from the camera and has no truth.
class Plant {
 public:
  virtual ~Plant() = default;
  virtual Machine& machine() = 0;
  virtual TurretImage Observe() = 0;
  virtual std::optional<MirrorPose> Truth() const { return std::nullopt; }
  virtual int Mirror() const = 0;  // the mirror over the camera, as the plant believes
};

// The simulated unit: a SimulatedMachine, each mirror's seating error on the turret, the renderer.
class SimulatedUnit final : public Plant {
 public:
  SimulatedUnit(const TurretSpec& spec, int mirror, const std::array<double, kAxisCount>& start,
                std::vector<MirrorPose> seats, uint64_t seed);
  Machine& machine() override { return machine_; }
  SimulatedMachine& sim() { return machine_; }
  const SimulatedMachine& sim() const { return machine_; }
  TurretImage Observe() override;
  std::optional<MirrorPose> Truth() const override;
  int Mirror() const override { return mirror_; }
  void SetMirror(int k) { mirror_ = k; }
  void CoverLabel(bool covered) { label_covered_ = covered; }
  int images() const { return images_; }
  double render_seconds() const { return render_seconds_; }

 private:
  const TurretSpec& spec_;
  SimulatedMachine machine_;
  std::vector<MirrorPose> seats_;
  int mirror_ = 0;
  bool label_covered_ = false;
  uint64_t seed_;
  int images_ = 0;
  double render_seconds_ = 0;
};

// A disturbed start for mirror k (the acceptance's): true axes that put the plate `lateral` (m) off the axis in a
// random direction, its axis tilted by `tilt` (rad) in a random direction and `height` (m) off (random sign),
// given the seat error; drawn from `seed`.
std::array<double, kAxisCount> DisturbedStart(const TurretSpec& spec, int k, const MirrorPose& seat, double focus,
                                              double lateral, double tilt, double height, uint64_t seed);
// Seating errors of every mirror on the turret, drawn from `seed`: up to 0.3 mm laterally and in height, 0.2 deg.
std::vector<MirrorPose> DrawSeats(const TurretSpec& spec, uint64_t seed);

struct PidGains {
  double kp = 0.0, ki = 1.0, kd = 0.0;  // dead-beat on this plant; `hovs rig align --kp --ki --kd` compares
  void Check(const std::string& where) const;
};

struct AlignOptions {
  int max_iterations = 30;
  // The loop stops when every measured deviation is within these (the acceptance is 0.05 mm and 0.02 deg: the
  // margin is for the measurement's own error and the last move's noise).
  double lateral_tolerance = 0.02e-3, height_tolerance = 0.02e-3;  // m
  double tilt_tolerance = 0.008 * M_PI / 180;                      // rad, per tilt axis
  double settle_timeout = 10;                                      // s of machine time per move
  PidGains lateral, height, tilt;
  LabelOptions label;
  int label_retries = 3;
  void Check(const std::string& where) const;
};

struct LoopStep {
  int iteration = 0;
  double time = 0;                          // machine clock, s
  std::optional<MirrorPose> measured;       // none when the label was not seen
  std::optional<MirrorPose> truth;          // simulation only
  std::array<double, kAxisCount> reported;  // before the command
  std::array<double, kAxisCount> command;   // sent (equal to reported for axes not moved)
  int markers = 0;
  double label_rms_px = 0;
  std::array<double, 5> label_sigma{};  // LabelMeasurement::sigma of the measurement
  std::string note;
};

struct AlignResult {
  bool converged = false;
  std::string failure;  // empty on success; names the axis or the measurement
  std::string failing;  // "x", "rod", ... or "label" or "" (not converged)
  std::vector<LoopStep> steps;
  std::optional<MirrorPose> final_measured, final_truth;
  int images = 0;
};

AlignResult Align(Plant& plant, const TurretSpec& spec, const AlignOptions& options);

// Refuses, before any run, an image resolution at which the label cannot measure mirror k's pose to the
// alignment's tolerances: a deviation whose noise (twice LabelPrecision's sigma: real measurements scatter up to
// that) exceeds twice its tolerance could never be seen within it, and the loop would chase its noise (and take
// that noise for a stuck axis). Throws
// hovs::Error(where) naming the deviation, both figures and the coarsest resolution worth trying.
void RequireLabelPrecision(const TurretSpec& spec, int k, const AlignOptions& options, const std::string& where);

}  // namespace hovs::rig
