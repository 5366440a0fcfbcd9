#include "rig/positioning.h"

#include <cmath>
#include <random>

#include "core/error.h"
#include "core/statistics.h"

namespace hovs::rig {
namespace {

constexpr double kDeg = M_PI / 180.0;
// The label's PnP sigma (LabelMeasurement::sigma) assumes independent corner errors; the measurements of a
// rendered unit scatter up to twice as much (the corners' errors are correlated, their refinement biased), so the
// loop and the resolution check take twice it as the noise.
constexpr double kSigmaMargin = 2.0;

// The controlled axes and the measured deviation each one cancels.
constexpr AxisId kControlled[] = {AxisId::kX, AxisId::kY, AxisId::kRod, AxisId::kTiltX, AxisId::kTiltY};
constexpr int kControlledCount = 5;

std::array<double, kControlledCount> Deviations(const MirrorPose& p) {
  return {p.offset.x(), p.offset.y(), p.offset.z(), p.rotation.x(), p.rotation.y()};
}

std::string Format(double v, const char* unit, double scale) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g %s", v * scale, unit);
  return buf;
}

}  // namespace

SimulatedUnit::SimulatedUnit(const TurretSpec& spec, int mirror, const std::array<double, kAxisCount>& start,
                             std::vector<MirrorPose> seats, uint64_t seed)
    : spec_(spec), machine_(spec.axes, start, seed), seats_(std::move(seats)), mirror_(mirror), seed_(seed) {
  HOVS_REQUIRE(seats_.size() == spec.mirrors.size(), "simulated unit", "one seat error per mirror needed");
}

std::optional<MirrorPose> SimulatedUnit::Truth() const {
  return PoseFromAxes(spec_, mirror_, machine_.TruePositions(), seats_.at(mirror_));
}

TurretImage SimulatedUnit::Observe() {
  const MirrorPose pose = *Truth();
  const double focus = machine_.TruePositions()[static_cast<int>(AxisId::kFocus)];
  TurretImage img =
      RenderTurret(spec_, mirror_, pose, focus, seed_ * 7919u + static_cast<uint64_t>(images_), label_covered_);
  ++images_;
  render_seconds_ += img.render_seconds;
  return img;
}

std::vector<MirrorPose> DrawSeats(const TurretSpec& spec, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<MirrorPose> out(spec.mirrors.size());
  for (auto& s : out) {
    s.offset = Vec3d(u(rng), u(rng), u(rng)) * 0.3e-3;
    s.rotation = Vec3d(u(rng), u(rng), 0) * 0.2 * kDeg;
  }
  return out;
}

std::array<double, kAxisCount> DisturbedStart(const TurretSpec& spec, int k, const MirrorPose& seat, double focus,
                                              double lateral, double tilt, double height, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI);
  const double a = angle(rng), b = angle(rng);
  const double sign = std::uniform_int_distribution<int>(0, 1)(rng) ? 1.0 : -1.0;
  std::array<double, kAxisCount> axes = spec.NominalAxes(k, focus);
  // The axes cancel the seat error and add the wanted deviation (the tilts to first order: the start's true
  // deviation is recorded by the loop, whatever it is exactly).
  axes[static_cast<int>(AxisId::kX)] = lateral * std::cos(a) - seat.offset.x();
  axes[static_cast<int>(AxisId::kY)] = lateral * std::sin(a) - seat.offset.y();
  axes[static_cast<int>(AxisId::kRod)] += sign * height - seat.offset.z();
  axes[static_cast<int>(AxisId::kTiltX)] = tilt * std::cos(b) - seat.rotation.x();
  axes[static_cast<int>(AxisId::kTiltY)] = tilt * std::sin(b) - seat.rotation.y();
  for (int i = 0; i < kAxisCount; ++i) {
    const AxisSpec& s = spec.axes[i];
    const AxisId id = AxisAt(i);
    HOVS_REQUIRE(axes[i] >= s.min && axes[i] <= s.max, spec.source + " (axes." + AxisName(id) + ")",
                 "the start asked of mirror '", spec.mirrors.at(k).id, "' puts axis ", AxisName(id), " at ",
                 AxisValueText(id, axes[i]), ", outside its travel [", AxisValueText(id, s.min), ", ",
                 AxisValueText(id, s.max), "]: ask for a smaller start or widen the travel");
  }
  return axes;
}

void PidGains::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(kp) && kp >= 0 && kp <= 2, where, "kp must be in [0, 2]");
  HOVS_REQUIRE(std::isfinite(ki) && ki >= 0 && ki <= 1, where, "ki must be in [0, 1]");
  HOVS_REQUIRE(kp + ki > 0, where, "kp and ki cannot both be 0");
  HOVS_REQUIRE(std::isfinite(kd) && kd >= 0 && kd <= 1, where, "kd must be in [0, 1]");
}

void AlignOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(max_iterations >= 1 && max_iterations <= 1000, where, "max_iterations must be 1..1000");
  HOVS_REQUIRE(lateral_tolerance > 0 && height_tolerance > 0 && tilt_tolerance > 0, where,
               "tolerances must be positive");
  HOVS_REQUIRE(settle_timeout > 0, where, "settle_timeout must be positive");
  HOVS_REQUIRE(label_retries >= 1 && label_retries <= 100, where, "label_retries must be 1..100");
  lateral.Check(where + " (lateral gains)");
  height.Check(where + " (height gains)");
  tilt.Check(where + " (tilt gains)");
  label.Check(where + " (label)");
}

AlignResult Align(Plant& plant, const TurretSpec& spec, const AlignOptions& o) {
  o.Check("align options");
  const int k = plant.Mirror();
  Machine& machine = plant.machine();
  const double tol[kControlledCount] = {o.lateral_tolerance, o.lateral_tolerance, o.height_tolerance, o.tilt_tolerance,
                                        o.tilt_tolerance};
  const PidGains* gains[kControlledCount] = {&o.lateral, &o.lateral, &o.height, &o.tilt, &o.tilt};
  const char* units[kControlledCount] = {"mm", "mm", "mm", "deg", "deg"};
  const double scales[kControlledCount] = {1e3, 1e3, 1e3, 1 / kDeg, 1 / kDeg};
  std::array<double, kControlledCount> integral{}, last_error{}, last_move{}, origin{};
  for (int j = 0; j < kControlledCount; ++j) origin[j] = machine.axis(kControlled[j]).Reported();
  std::array<bool, kControlledCount> saturated{};
  // Fault evidence per axis: commanded and measured motion over recent moves, and the label's measurement noise
  // (the median of its measurements' sigmas): motion is only judged where it stands out of that noise.
  std::array<double, kControlledCount> stuck_commanded{}, stuck_measured{};
  std::array<int, kControlledCount> short_moves{}, stuck_moves{};
  std::array<std::vector<double>, kControlledCount> sigmas;
  bool have_last = false;
  int label_failures = 0;
  AlignResult r;
  const auto fail = [&](const std::string& failing, const std::string& why) {
    r.failing = failing;
    r.failure = why;
  };
  for (int it = 0; it < o.max_iterations && r.failure.empty(); ++it) {
    LoopStep step;
    step.iteration = it;
    step.time = machine.Now();
    for (int i = 0; i < kAxisCount; ++i) step.reported[i] = step.command[i] = machine.axis(AxisAt(i)).Reported();
    step.truth = plant.Truth();
    const TurretImage image = plant.Observe();
    LabelMeasurement m;
    try {
      m = MeasureLabel(image, spec, k, o.label);
    } catch (const Error& e) {
      step.note = e.what();
      r.steps.push_back(step);
      if (++label_failures >= o.label_retries)
        fail("label", "the label could not be measured in " + std::to_string(label_failures) +
                          " images in a row; last: " + e.message());
      continue;
    }
    label_failures = 0;
    step.measured = m.pose;
    step.markers = m.markers;
    step.label_rms_px = m.rms_px;
    step.label_sigma = m.sigma;
    const auto e = Deviations(m.pose);
    std::array<double, kControlledCount> noise{};
    for (int j = 0; j < kControlledCount; ++j) {
      sigmas[j].push_back(m.sigma[j]);
      noise[j] = kSigmaMargin * Median(sigmas[j]);
    }
    bool within = true;
    for (int j = 0; j < kControlledCount; ++j) within = within && std::abs(e[j]) <= tol[j];
    if (within) {
      step.note = "converged";
      r.steps.push_back(step);
      r.converged = true;
      break;
    }
    // Fault checks on the motion since the last measurement.
    if (have_last) {
      for (int j = 0; j < kControlledCount && r.failure.empty(); ++j) {
        const double commanded = last_move[j], measured = e[j] - last_error[j];
        const std::string name = AxisName(kControlled[j]);
        stuck_commanded[j] += std::abs(commanded);
        stuck_measured[j] += commanded == 0 ? 0 : measured * (commanded > 0 ? 1 : -1);
        stuck_moves[j] += commanded != 0;
        // The measured motion over those moves is a sum of measurement differences: its noise is about
        // sigma sqrt(2 moves). A stuck axis is called only when the commanded motion is six times that.
        const double motion_noise = noise[j] * std::sqrt(2.0 * std::max(1, stuck_moves[j]));
        if (stuck_commanded[j] >= 5 * tol[j] && stuck_commanded[j] >= 6 * motion_noise &&
            std::abs(stuck_measured[j]) < 0.2 * stuck_commanded[j])
          fail(name, "axis " + name + " does not move: commanded " + Format(stuck_commanded[j], units[j], scales[j]) +
                         " in all, the label measured " + Format(stuck_measured[j], units[j], scales[j]) + " (stuck)");
        // Lost steps: a move that a 20 % shortfall makes stand out of the noise by three sigmas.
        if (std::abs(commanded) >= 10 * tol[j] && std::abs(commanded) >= 15 * std::sqrt(2.0) * noise[j]) {
          const double ratio = measured / commanded;
          short_moves[j] = ratio < 0.8 ? short_moves[j] + 1 : 0;
          if (short_moves[j] >= 2 && r.failure.empty())
            fail(name, "axis " + name + " loses steps: the label measured " + Format(ratio * 100, "%", 1) +
                           " of the commanded " + Format(commanded, units[j], scales[j]) +
                           " (twice in a row); home the axis");
        }
        if (std::abs(measured) >= 0.2 * std::abs(commanded) && commanded != 0 && std::abs(measured) > 3 * noise[j])
          stuck_commanded[j] = stuck_measured[j] = 0, stuck_moves[j] = 0;
      }
      if (!r.failure.empty()) {
        step.note = r.failure;
        r.steps.push_back(step);
        break;
      }
    }
    // PID per axis in positional form about the loop's starting command (the measurement is an absolute
    // deviation and the axis holds its position, so the integral is the main term and kp damps it), limited to
    // the travel, with conditional integration.
    for (int j = 0; j < kControlledCount; ++j) {
      const int a = static_cast<int>(kControlled[j]);
      const AxisSpec& s = spec.axes[a];
      const PidGains& g = *gains[j];
      if (!saturated[j]) integral[j] += e[j];
      const double derivative = have_last ? e[j] - last_error[j] : 0.0;
      const double u = -(g.kp * e[j] + g.ki * integral[j] + g.kd * derivative);
      double target = origin[j] + u;
      saturated[j] = target < s.min || target > s.max;
      if (saturated[j]) integral[j] -= e[j];  // anti-windup: this step's error is not integrated
      target = std::clamp(target, s.min, s.max);
      step.command[a] = target;
      last_move[j] = target - step.reported[a];
      last_error[j] = e[j];
      machine.axis(kControlled[j]).MoveTo(target);
    }
    have_last = true;
    r.steps.push_back(step);
    machine.WaitIdle(o.settle_timeout);
  }
  if (!r.converged && r.failure.empty())
    fail("", "not converged in " + std::to_string(o.max_iterations) + " iterations");
  for (auto it = r.steps.rbegin(); it != r.steps.rend(); ++it)
    if (it->measured) {
      r.final_measured = it->measured;
      break;
    }
  r.final_truth = plant.Truth();
  return r;
}

void RequireLabelPrecision(const TurretSpec& spec, int k, const AlignOptions& o, const std::string& where) {
  o.Check("align options");
  const std::array<double, kControlledCount> sigma = LabelPrecision(spec, k, o.label, 1);
  const double tol[kControlledCount] = {o.lateral_tolerance, o.lateral_tolerance, o.height_tolerance, o.tilt_tolerance,
                                        o.tilt_tolerance};
  const char* names[kControlledCount] = {"the lateral offset x", "the lateral offset y", "the height",
                                         "the tilt about x", "the tilt about y"};
  const char* units[kControlledCount] = {"mm", "mm", "mm", "deg", "deg"};
  const double scales[kControlledCount] = {1e3, 1e3, 1e3, 1 / kDeg, 1 / kDeg};
  int worst = 0;  // the deviation whose noise is largest against its tolerance
  for (int j = 1; j < kControlledCount; ++j)
    if (sigma[j] / tol[j] > sigma[worst] / tol[worst]) worst = j;
  const int j = worst;
  if (kSigmaMargin * sigma[j] <= 2 * tol[j]) return;
  // The sigma grows about as the square of the pixel size (coarser pixels and less sharp corners); the
  // suggestion is the coarsest resolution below that which divides the image.
  int finer = std::max(1, static_cast<int>(std::floor(spec.downscale * std::sqrt(tol[j] / sigma[j]))));
  while (finer > 1 && (spec.camera.width % finer != 0 || spec.camera.height % finer != 0)) --finer;
  const PinholeCamera<double> cam = spec.ImageCamera();
  throw Error(where, "at " + std::to_string(cam.width) + " x " + std::to_string(cam.height) + " pixels (1/" +
                         std::to_string(spec.downscale) + " of the camera's) the label measures " + names[j] +
                         " of mirror '" + spec.mirrors.at(k).id + "' to " + Format(sigma[j], units[j], scales[j]) +
                         " (1 sigma; real measurements scatter up to twice as much), more than the alignment's "
                         "tolerance of " +
                         Format(tol[j], units[j], scales[j]) +
                         ": the loop cannot align there; use a finer resolution "
                         "(--downscale " +
                         std::to_string(finer) + " or less)");
}

}  // namespace hovs::rig
