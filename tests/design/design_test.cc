// The design study: formulas against the reference sheet, the article's acceptance (a = 48, b = 44), optimum
// feasibility and optimality against the sweep, every objective, and config validation.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "design/config.h"
#include "design/design.h"

namespace hovs::design {
namespace {

constexpr double kDeg = M_PI / 180;

DesignConfig Reference() { return LoadDesignConfig(std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml"); }

TEST(DesignMetrics, MatchTheReferenceSheetFormulas) {
  const DesignConfig cfg = Reference();
  const DesignPoint p{0.048, 0.044, 0.080};
  const Metrics m = Evaluate(p, cfg.problem);
  // Independent closed forms from reference-system.md.
  const double c = std::sqrt(0.048 * 0.048 + 0.044 * 0.044);
  const double z_rim = -c + 0.048 * std::sqrt(1 + 0.04 * 0.04 / (0.044 * 0.044));
  EXPECT_NEAR(m.c, c, 1e-15);
  EXPECT_NEAR(m.system_length, 2 * c, 1e-15);
  EXPECT_NEAR(m.rim_z, z_rim, 1e-15);
  EXPECT_NEAR(m.upper_deg, std::atan2(z_rim, 0.04) / kDeg, 1e-12);
  EXPECT_NEAR(m.lower_deg, std::atan2(-2 * c, 0.01) / kDeg, 1e-12);
  EXPECT_NEAR(m.field_deg, m.upper_deg - m.lower_deg, 1e-12);
  EXPECT_NEAR(m.rim_radius_px, 0.016 * 0.04 / (z_rim + 2 * c) / 4.54e-6, 1e-8);
  EXPECT_NEAR(m.sag, z_rim - (0.048 - c), 1e-15);
  EXPECT_NEAR(m.ground_radius_inner, 1.3 / std::tan(-m.lower_deg * kDeg), 1e-12);
  EXPECT_NEAR(m.ground_radius_outer, 1.3 / std::tan(-m.upper_deg * kDeg), 1e-9);
  // The article's numbers: c = 65.115 mm, rim below the horizon, rim radius inside 1100 px.
  EXPECT_NEAR(m.c * 1e3, 65.115, 5e-4);
  EXPECT_LT(m.upper_deg, 0);
  EXPECT_LT(m.rim_radius_px, 1100);
  EXPECT_GT(m.rim_radius_px, 1080);
}

TEST(DesignMetrics, ALensWiderThanTheMirrorViolatesTheReflectionConstraint) {
  DesignConfig cfg = Reference();
  const DesignPoint p{0.048, 0.044, 0.080};
  auto g = EvaluateConstraints(Evaluate(p, cfg.problem), cfg.problem);
  ASSERT_EQ(g.size(), 3u);
  EXPECT_EQ(g[2].name, "camera_reflection_inside_rim");
  EXPECT_LT(g[2].value, 0);
  // A deep mirror (upper bound -56 deg) with a 30 cm lens: the lens rim is seen above the mirror's rim ray.
  cfg.problem.camera.lens_aperture = 0.30;
  g = EvaluateConstraints(Evaluate(DesignPoint{0.020, 0.080, 0.080}, cfg.problem), cfg.problem);
  EXPECT_GT(g[2].value, 0);
}

TEST(DesignMetrics, RadialResolutionIsTheDerivativeOfTheImageRadius) {
  const DesignConfig cfg = Reference();
  const DesignPoint p{0.048, 0.044, 0.080};
  const auto res = RadialResolution(p, cfg.problem.camera, 50);
  ASSERT_EQ(res.size(), 50u);
  // Closed form of the aligned rig: rho(e) = fx * eta * cos(e) / (xi - sin(e)).
  const double a = p.a, b = p.b, c = std::hypot(a, b), fx = 0.016 / 4.54e-6;
  const double xi = 2 * a * c / (2 * a * a + b * b), eta = b * b / (2 * a * a + b * b);
  const auto rho = [&](double e) { return fx * eta * std::cos(e) / (xi - std::sin(e)); };
  for (const auto& r : res) {
    const double e = r.elevation_deg * kDeg, h = 1e-6;
    EXPECT_NEAR(r.rho_px, rho(e), 1e-8);
    EXPECT_NEAR(r.px_per_deg, std::abs(rho(e + h) - rho(e - h)) / (2 * h) * kDeg, 1e-5);
  }
  EXPECT_LT(res.front().px_per_deg, res.back().px_per_deg) << "resolution grows towards the rim";
}

TEST(DesignStudy, ArticleAcceptance) {
  const DesignConfig cfg = Reference();
  const SweepResult sweep = Sweep(cfg.problem, cfg.sweep);
  const Optimum opt = OptimizeContinuous(cfg.problem, sweep);
  // Every constraint satisfied to 1e-6 (in its unit: degrees, pixels).
  for (const auto& g : opt.constraints) EXPECT_LE(g.value, 1e-6) << g.name;
  // The horizon and rim constraints are both active at the smallest system.
  ASSERT_GE(opt.constraints.size(), 2u);
  EXPECT_EQ(opt.constraints[0].name, "upper_bound_below_limit");
  EXPECT_EQ(opt.constraints[1].name, "rim_inside_image");
  EXPECT_GT(opt.constraints[0].value, -1e-3);
  EXPECT_GT(opt.constraints[1].value, -1e-3);
  // No feasible grid point beats it.
  for (size_t i = 0; i < sweep.size(); ++i) {
    if (sweep.violated[i] == 0) { ASSERT_GE(sweep.objective[i], opt.objective - 1e-12) << "grid point " << i; }
  }
  // The best integer-millimetre design is the article's a = 48, b = 44.
  const auto mm = OptimizeIntegerMillimetre(cfg.problem);
  ASSERT_TRUE(mm.has_value());
  EXPECT_NEAR(mm->metrics.p.a, 0.048, 1e-12);
  EXPECT_NEAR(mm->metrics.p.b, 0.044, 1e-12);
  EXPECT_LE(mm->max_violation, 0.0);
  EXPECT_GE(mm->objective, opt.objective);
}

TEST(DesignStudy, EveryObjectiveGivesAFeasibleOptimumNoGridPointBeats) {
  DesignConfig cfg = Reference();
  cfg.sweep = {121, 121, 1};
  cfg.problem.constraints.min_vertical_field_deg = 70.0;  // keeps the widest field bounded by the rim
  for (Objective o : {Objective::kSmallestSystem, Objective::kWidestField, Objective::kLargestRim}) {
    cfg.problem.objective = o;
    const SweepResult sweep = Sweep(cfg.problem, cfg.sweep);
    const Optimum opt = OptimizeContinuous(cfg.problem, sweep);
    EXPECT_LE(opt.max_violation, 0.0) << ToString(o);
    const auto best = sweep.BestFeasible();
    ASSERT_TRUE(best.has_value());
    EXPECT_LE(opt.objective, sweep.objective[*best] + 1e-12) << ToString(o);
  }
}

TEST(DesignStudy, OptimisesTheRimDiameterWhenAsked) {
  DesignConfig cfg = Reference();
  cfg.problem.d = {0.060, 0.100};
  cfg.sweep = {61, 61, 9};
  const SweepResult sweep = Sweep(cfg.problem, cfg.sweep);
  const Optimum opt = OptimizeContinuous(cfg.problem, sweep);
  EXPECT_LE(opt.max_violation, 0.0);
  for (size_t i = 0; i < sweep.size(); ++i) {
    if (sweep.violated[i] == 0) { ASSERT_GE(sweep.objective[i], opt.objective - 1e-12); }
  }
  // A smaller rim allows a smaller system.
  EXPECT_LT(opt.metrics.p.d, 0.080);
}

TEST(DesignStudy, EmptyFeasibleSetIsAnError) {
  DesignConfig cfg = Reference();
  cfg.problem.constraints.min_rim_radius_px = 1200;  // more than the 1100 px limit
  cfg.sweep = {41, 41, 1};
  const SweepResult sweep = Sweep(cfg.problem, cfg.sweep);
  EXPECT_FALSE(sweep.BestFeasible().has_value());
  EXPECT_THROW(OptimizeContinuous(cfg.problem, sweep), Error);
  EXPECT_FALSE(OptimizeIntegerMillimetre(cfg.problem).has_value());
}

// ---- Config validation --------------------------------------------------------------------------------
std::string RefText() {
  return R"(camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.020}
mirror: {rim_diameter: 0.080}
)";
}

void ExpectError(const std::string& text, const std::string& needle) {
  try {
    ParseDesignConfig(text, "test.yaml");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("test.yaml"), std::string::npos) << "names the file: " << e.what();
  }
}

TEST(DesignConfig, AcceptsAMinimalConfig) {
  const DesignConfig c = ParseDesignConfig(RefText(), "test.yaml");
  EXPECT_EQ(c.problem.d.min, 0.080);
  EXPECT_EQ(c.problem.objective, Objective::kSmallestSystem);
}

TEST(DesignConfig, RejectsBadInput) {
  ExpectError(RefText() + "colour: red\n", "unknown key 'colour'");
  ExpectError(RefText() + "mirror: {rim_diameter: 0.06}\n", "duplicate key 'mirror'");
  ExpectError(RefText() + "constraints: {max_upper_elevation: 0}\n", "unknown key 'max_upper_elevation'");
  ExpectError(
      "camera: {focal_length: -0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.02}\n"
      "mirror: {rim_diameter: 0.080}\n",
      "focal length must be positive");
  ExpectError(
      "camera: {focal_length: .nan, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.02}\n"
      "mirror: {rim_diameter: 0.080}\n",
      "finite");
  ExpectError(RefText() + "search: {b: [0.0, 0.08]}\n", "b minimum must be positive");
  ExpectError(RefText() + "search: {b: [-0.01, 0.08]}\n", "b minimum must be positive");
  ExpectError(RefText() + "search: {a: [0.08, 0.02]}\n", "exceeds maximum");
  ExpectError(
      "camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.02}\n"
      "mirror: {rim_diameter: -0.08}\n",
      "d minimum must be positive");
  ExpectError(RefText() + "objective: biggest\n", "unknown objective 'biggest'");
  ExpectError(RefText() + "search: {grid: [1, 100]}\n", "at least 2 x 2");
  ExpectError(RefText() + "search: {grid: [100.5, 100]}\n", "expected an integer");
  ExpectError(RefText() + "mounting_height: tall\n", "expected a number");
  ExpectError("camera: {focal_length: 0.016}\nmirror: {rim_diameter: 0.08}\n", "missing 'camera.pixel_pitch'");
  ExpectError("camera: [1, 2\n", "not valid YAML");
  ExpectError(RefText() + "search: {d: [0.06, 0.1]}\n", "not both");
}

TEST(DesignConfig, MissingFileIsAnError) { EXPECT_THROW(LoadDesignConfig("/nonexistent/design.yaml"), Error); }

}  // namespace
}  // namespace hovs::design
