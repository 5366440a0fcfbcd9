#include "rig/actuators.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"

namespace hovs::rig {

const char* AxisName(AxisId axis) {
  static const char* const kNames[kAxisCount] = {"turret", "rod", "x", "y", "tilt_x", "tilt_y", "focus"};
  return kNames[static_cast<int>(axis)];
}

bool AxisIsAngular(AxisId axis) { return axis == AxisId::kTurret || axis == AxisId::kTiltX || axis == AxisId::kTiltY; }

std::string AxisValueText(AxisId axis, double value) {
  return AxisIsAngular(axis) ? FormatNumber("%.6g", value * 180 / M_PI) + " deg" : FormatNumber("%.6g", value) + " m";
}

void AxisSpec::Check(const std::string& where, AxisId axis) const {
  const auto text = [&](double v) { return AxisValueText(axis, v); };
  HOVS_REQUIRE(std::isfinite(min) && std::isfinite(max) && min < max, where, "travel [", text(min), ", ", text(max),
               "] must be finite with min < max");
  // A motor step so coarse that the travel holds few positions cannot position anything.
  HOVS_REQUIRE(std::isfinite(step) && step > 0 && step <= 0.01 * (max - min), where, "the step ", text(step),
               " must be positive and at most a hundredth of the travel (", text(max - min), ")");
  HOVS_REQUIRE(std::isfinite(time_constant) && time_constant > 0 && time_constant <= 100, where,
               "time_constant must be in (0, 100] s (got ", FormatNumber("%.6g", time_constant), " s)");
  HOVS_REQUIRE(std::isfinite(backlash) && backlash >= 0 && backlash < 0.1 * (max - min), where, "backlash ",
               text(backlash), " must be >= 0 and below a tenth of the travel (", text(max - min), ")");
  HOVS_REQUIRE(std::isfinite(noise) && noise >= 0 && noise < 0.1 * (max - min), where, "noise ", text(noise),
               " must be >= 0 and below a tenth of the travel (", text(max - min), ")");
}

SimulatedAxis::SimulatedAxis(AxisId id, const AxisSpec& spec, double start, uint64_t seed)
    : id_(id), spec_(spec), rng_(seed) {
  spec_.Check(std::string("axis ") + AxisName(id), id);
  HOVS_REQUIRE(start >= spec.min && start <= spec.max, std::string("axis ") + AxisName(id), "start ",
               AxisValueText(id, start), " outside the travel [", AxisValueText(id, spec.min), ", ",
               AxisValueText(id, spec.max), "]");
  commanded_ = goal_ = motor_ = output_ = start;
}

void SimulatedAxis::MoveTo(double target) {
  const std::string where = std::string("axis ") + AxisName(id_);
  HOVS_REQUIRE(std::isfinite(target), where, "target is not a finite number");
  const double q = spec_.min + std::round((target - spec_.min) / spec_.step) * spec_.step;
  HOVS_REQUIRE(q >= spec_.min - 1e-12 && q <= spec_.max + 1e-12, where, "target ", AxisValueText(id_, target),
               " outside the travel [", AxisValueText(id_, spec_.min), ", ", AxisValueText(id_, spec_.max), "]");
  if (q == commanded_) return;
  // Lost steps: the motor covers only part of the move; the controller counts it all.
  goal_ = motor_ + (q - commanded_) * (1.0 - fault_.lost_steps);
  commanded_ = q;
  moving_ = true;
}

void SimulatedAxis::Advance(double dt) {
  if (!moving_) return;
  motor_ += (goal_ - motor_) * (1.0 - std::exp(-dt / spec_.time_constant));
  const bool done = std::abs(goal_ - motor_) < 0.01 * spec_.step;
  if (done) motor_ = goal_;
  if (!fault_.stuck) {
    // The output is dragged by the motor once the dead band is taken up.
    const double half = 0.5 * spec_.backlash;
    if (motor_ - output_ > half) output_ = motor_ - half;
    if (output_ - motor_ > half) output_ = motor_ + half;
  }
  if (done) {
    moving_ = false;
    if (!fault_.stuck && spec_.noise > 0) offset_ = std::normal_distribution<double>(0, spec_.noise)(rng_);
  }
}

SimulatedMachine::SimulatedMachine(const std::array<AxisSpec, kAxisCount>& specs,
                                   const std::array<double, kAxisCount>& start, uint64_t seed, double tick)
    : tick_(tick) {
  HOVS_REQUIRE(std::isfinite(tick) && tick > 0 && tick <= 1, "simulated machine", "tick must be in (0, 1] s");
  for (int i = 0; i < kAxisCount; ++i)
    axes_[i] = std::make_unique<SimulatedAxis>(AxisAt(i), specs[i], start[i], seed * 1000003u + 7919u * (i + 1));
}

void SimulatedMachine::Advance(double dt) {
  for (auto& a : axes_) a->Advance(dt);
  now_ += dt;
}

void SimulatedMachine::WaitIdle(double timeout_s) {
  const double end = now_ + timeout_s;
  const auto any_moving = [&] {
    for (const auto& a : axes_)
      if (a->Moving()) return true;
    return false;
  };
  while (any_moving() && now_ < end) Advance(tick_);
  if (any_moving()) {
    std::string names;
    for (const auto& a : axes_)
      if (a->Moving()) names += (names.empty() ? "" : ", ") + std::string(AxisName(a->id()));
    throw Error("simulated machine", "axes still moving after " + std::to_string(timeout_s) + " s: " + names);
  }
}

std::array<double, kAxisCount> SimulatedMachine::TruePositions() const {
  std::array<double, kAxisCount> out;
  for (int i = 0; i < kAxisCount; ++i) out[i] = axes_[i]->Output();
  return out;
}

}  // namespace hovs::rig
