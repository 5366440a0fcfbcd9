// The simulated axes: quantisation, first-order lag, backlash, limits, repeatability noise and injected faults,
// each checked against its closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "rig/actuators.h"

namespace hovs::rig {
namespace {

AxisSpec Spec() {
  AxisSpec s;
  s.min = -0.01, s.max = 0.01, s.step = 1e-6, s.time_constant = 0.05;
  return s;
}

TEST(SimulatedAxis, QuantisesCommandsAndFollowsWithAFirstOrderLag) {
  SimulatedAxis a(AxisId::kX, Spec(), 0.0, 1);
  a.MoveTo(1.23456e-3);
  EXPECT_NEAR(a.Reported(), 1.235e-3, 1e-12);  // whole steps
  EXPECT_TRUE(a.Moving());
  a.Advance(0.05);  // one time constant: 1 - 1/e of the way
  EXPECT_NEAR(a.Output(), 1.235e-3 * (1 - std::exp(-1.0)), 1e-9);
  for (int i = 0; i < 100 && a.Moving(); ++i) a.Advance(0.01);
  EXPECT_FALSE(a.Moving());
  EXPECT_NEAR(a.Output(), 1.235e-3, 1e-12);
}

TEST(SimulatedAxis, BacklashLosesHalfTheDeadBandOnEachSideAfterAReversal) {
  AxisSpec s = Spec();
  s.backlash = 20e-6;
  SimulatedAxis a(AxisId::kX, s, 0.0, 1);
  const auto settle = [&] {
    for (int i = 0; i < 1000 && a.Moving(); ++i) a.Advance(0.01);
  };
  a.MoveTo(1e-3);
  settle();
  EXPECT_NEAR(a.Output(), 1e-3 - 10e-6, 1e-10);  // dragged from behind
  a.MoveTo(0.5e-3);
  settle();
  EXPECT_NEAR(a.Output(), 0.5e-3 + 10e-6, 1e-10);  // reversed: the dead band is crossed first
  a.MoveTo(0.505e-3);                              // inside the dead band: the output does not move
  settle();
  EXPECT_NEAR(a.Output(), 0.5e-3 + 10e-6, 1e-10);
}

TEST(SimulatedAxis, RefusesTargetsOutsideItsTravelNamingTheAxis) {
  SimulatedAxis a(AxisId::kTiltY, Spec(), 0.0, 1);
  try {
    a.MoveTo(0.02);
    FAIL() << "accepted a target outside the travel";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("axis tilt_y"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside the travel"), std::string::npos) << e.what();
  }
  EXPECT_THROW(a.MoveTo(std::nan("")), Error);
  EXPECT_EQ(a.Reported(), 0.0);
}

TEST(SimulatedAxis, RepeatabilityNoiseHasItsSigma) {
  AxisSpec s = Spec();
  s.noise = 2e-6;
  SimulatedAxis a(AxisId::kX, s, 0.0, 7);
  double sum = 0, sum2 = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    a.MoveTo(i % 2 ? 1e-3 : 2e-3);
    for (int t = 0; t < 1000 && a.Moving(); ++t) a.Advance(0.01);
    const double err = a.Output() - a.Reported();
    sum += err, sum2 += err * err;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0, 0.2e-6);
  EXPECT_NEAR(sd, 2e-6, 0.2e-6);
}

TEST(SimulatedAxis, FaultsStuckAndLostSteps) {
  SimulatedAxis stuck(AxisId::kRod, Spec(), 0.0, 1);
  stuck.SetFault({true, 0.0});
  stuck.MoveTo(1e-3);
  for (int i = 0; i < 1000 && stuck.Moving(); ++i) stuck.Advance(0.01);
  EXPECT_NEAR(stuck.Reported(), 1e-3, 1e-12);  // the controller believes it moved
  EXPECT_EQ(stuck.Output(), 0.0);

  SimulatedAxis lossy(AxisId::kRod, Spec(), 0.0, 1);
  lossy.SetFault({false, 0.25});
  lossy.MoveTo(2e-3);
  for (int i = 0; i < 1000 && lossy.Moving(); ++i) lossy.Advance(0.01);
  EXPECT_NEAR(lossy.Output(), 1.5e-3, 1e-9);
}

TEST(SimulatedMachine, WaitIdleAdvancesTheClockAndTimesOut) {
  std::array<AxisSpec, kAxisCount> specs;
  specs.fill(Spec());
  SimulatedMachine m(specs, {}, 3);
  m.axis(AxisId::kX).MoveTo(5e-3);
  m.WaitIdle(5.0);
  EXPECT_GT(m.Now(), 0.3);  // about ln(5e-3 / 1e-8) time constants
  EXPECT_LT(m.Now(), 1.0);
  EXPECT_NEAR(m.TruePositions()[static_cast<int>(AxisId::kX)], 5e-3, 1e-12);
  m.axis(AxisId::kY).MoveTo(-5e-3);
  try {
    m.WaitIdle(0.01);
    FAIL() << "no timeout";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("still moving after"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(": y"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hovs::rig
