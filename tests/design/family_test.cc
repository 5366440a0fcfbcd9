// The turret's mirror family: every member is the optimum of its objective (against a brute-force grid over the
// whole search box and a fine grid around it), the chosen integer-millimetre mirror is the enumeration's best,
// the reference member is the article's 48 / 44, the closed-form resolutions agree with the core's projection,
// and the rod travel is honoured.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "design/config.h"
#include "design/design.h"
#include "design/family.h"
#include "design/study.h"

namespace hovs::design {
namespace {

constexpr double kDeg = M_PI / 180;

DesignConfig Turret() {
  DesignConfig cfg = LoadDesignConfig(std::string(HOVS_SOURCE_DIR) + "/design/turret.yaml");
  cfg.sweep = {81, 81, 1};  // the solvers' start; the test's own grids are finer
  return cfg;
}

// The best feasible objective on an n x n grid over [a0, a1] x [b0, b1], evaluated point by point.
struct GridBest {
  double objective = std::numeric_limits<double>::infinity();
  DesignPoint p;
};
GridBest BruteForce(const DesignProblem& problem, double a0, double a1, double b0, double b1, int n) {
  GridBest best;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const DesignPoint p{a0 + (a1 - a0) * i / (n - 1), b0 + (b1 - b0) * j / (n - 1), problem.d.min};
      const Metrics m = Evaluate(p, problem);
      if (MaxViolation(EvaluateConstraints(m, problem)) > 0) continue;
      const double o = ObjectiveValue(m, problem.objective);
      if (o < best.objective) best = {o, p};
    }
  return best;
}

// Magnitude of an objective's typical value, for relative tolerances.
double Scale(double v) { return std::max(std::abs(v), 1e-3); }

class Family : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    config_ = new DesignConfig(Turret());
    family_ = new MirrorFamily(RunFamilyStudy(*config_));
  }
  static void TearDownTestSuite() {
    delete family_;
    delete config_;
  }
  static DesignConfig* config_;
  static MirrorFamily* family_;
};
DesignConfig* Family::config_ = nullptr;
MirrorFamily* Family::family_ = nullptr;

TEST_F(Family, EveryMemberIsTheOptimumOfItsObjective) {
  ASSERT_EQ(family_->mirrors.size(), 4u);
  for (const FamilyMirror& f : family_->mirrors) {
    SCOPED_TRACE(f.member.name);
    const DesignProblem& p = f.problem;
    const Optimum& o = f.continuous;
    EXPECT_LE(o.max_violation, 0);
    // No point of a 241 x 241 grid over the whole box beats the continuous optimum ...
    const GridBest global = BruteForce(p, p.a.min, p.a.max, p.b.min, p.b.max, 241);
    ASSERT_TRUE(std::isfinite(global.objective));
    EXPECT_LE(o.objective, global.objective + 1e-9 * Scale(global.objective));
    // ... and the grid's best lies near it: the optimum is not a different basin.
    EXPECT_LT(global.objective - o.objective, 0.02 * Scale(o.objective));
    // Nor does any point of a fine grid of +-1 mm around it (0.025 mm steps).
    const GridBest local =
        BruteForce(p, std::max(p.a.min, o.metrics.p.a - 1e-3), std::min(p.a.max, o.metrics.p.a + 1e-3),
                   std::max(p.b.min, o.metrics.p.b - 1e-3), std::min(p.b.max, o.metrics.p.b + 1e-3), 81);
    EXPECT_LE(o.objective, local.objective + 1e-6 * Scale(local.objective));
  }
}

TEST_F(Family, ChosenMirrorsAreTheIntegerMillimetreBestAndWithinTheRodTravel) {
  const Range travel = *config_->problem.constraints.rod_travel;
  for (const FamilyMirror& f : family_->mirrors) {
    SCOPED_TRACE(f.member.name);
    ASSERT_TRUE(f.integer_mm.has_value());
    // Independent enumeration of every integer-millimetre (a, b) in the box.
    const GridBest grid = BruteForce(f.problem, 0.020, 0.080, 0.020, 0.080, 61);
    EXPECT_NEAR(f.Chosen().metrics.p.a, grid.p.a, 1e-12);
    EXPECT_NEAR(f.Chosen().metrics.p.b, grid.p.b, 1e-12);
    const Metrics& m = f.Chosen().metrics;
    EXPECT_LE(f.Chosen().max_violation, 0);
    EXPECT_GE(m.plate_height, travel.min);
    EXPECT_LE(m.plate_height, travel.max);
    EXPECT_LE(m.upper_deg, 0);
    EXPECT_LE(m.rim_radius_px, 1100);
    EXPECT_LE(m.reflection_radius_px, m.rim_radius_px);
  }
  // The reference member is the article's choice; the four mirrors are distinct.
  EXPECT_NEAR(family_->mirrors[0].Chosen().metrics.p.a, 0.048, 1e-12);
  EXPECT_NEAR(family_->mirrors[0].Chosen().metrics.p.b, 0.044, 1e-12);
  EXPECT_TRUE(family_->coincident.empty());
}

TEST_F(Family, EachMirrorWinsItsOwnObjective) {
  // Every member's chosen design is at least as good for its objective as every other member's.
  for (const FamilyMirror& f : family_->mirrors)
    for (const FamilyMirror& g : family_->mirrors) {
      const Optimum other = EvaluateDesign(g.Chosen().metrics.p, f.problem, "other member");
      if (other.max_violation > 0) continue;
      EXPECT_LE(f.Chosen().objective, other.objective + 1e-12) << f.member.name << " vs " << g.member.name;
    }
}

TEST(FamilyResolution, ClosedFormMatchesTheCoreProjection) {
  const DesignConfig cfg = Turret();
  for (const DesignPoint p : {DesignPoint{0.048, 0.044, 0.08}, DesignPoint{0.044, 0.062, 0.08}}) {
    const Metrics m = Evaluate(p, cfg.problem);
    const CatadioptricCamera<double> rig = RigOf(p, cfg.problem.camera);
    // Central difference of the core's projection of a direction at elevation e.
    const auto rho = [&](double e) {
      Vec2<double> uv = Vec2<double>::Zero();
      EXPECT_EQ(rig.ImgFromMirrorSvp(Vec3<double>(std::cos(e), 0, std::sin(e)), &uv), ProjectionStatus::kOk);
      return uv(0) - rig.camera.cx;
    };
    const auto resolution = [&](double e_deg) {
      const double h = 1e-5;
      return std::abs(rho((e_deg + h) * kDeg) - rho((e_deg - h) * kDeg)) / (2 * h);
    };
    EXPECT_NEAR(m.upper_px_per_deg, resolution(m.upper_deg - 1e-4), 1e-3 * m.upper_px_per_deg);
    if (m.upper_deg >= cfg.problem.long_range_elevation_deg)
      EXPECT_NEAR(m.long_range_px_per_deg, resolution(cfg.problem.long_range_elevation_deg),
                  1e-4 * m.long_range_px_per_deg);
    else
      EXPECT_EQ(m.long_range_px_per_deg, 0);
    // Near-ground coverage: the image annulus between the camera's reflection and the 3 m ground ring.
    const double e_ground = -std::atan2(cfg.problem.mounting_height, cfg.problem.near_ground_radius) / kDeg;
    const double rho_g = m.upper_deg > e_ground ? rho(e_ground * kDeg) : m.rim_radius_px;
    EXPECT_NEAR(m.near_ground_mpx, M_PI * (rho_g * rho_g - m.reflection_radius_px * m.reflection_radius_px) * 1e-6,
                1e-9);
  }
}

TEST(FamilyConfig, BadFamiliesAreRefusedNamingTheEntry) {
  const std::string base = R"(
camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.02}
mirror: {rim_diameter: 0.08}
)";
  const auto message = [&](const std::string& extra) {
    try {
      ParseDesignConfig(base + extra, "t.yaml");
    } catch (const Error& e) { return std::string(e.what()); }
    return std::string("accepted");
  };
  EXPECT_NE(message("family: [{name: x, objective: fastest}]\n").find("unknown objective 'fastest'"),
            std::string::npos);
  EXPECT_NE(
      message("family: [{name: x, objective: widest_field}, {name: x, objective: largest_rim}]\n").find("given twice"),
      std::string::npos);
  EXPECT_NE(message("family: [{name: x}]\n").find("needs a name and an objective"), std::string::npos);
  EXPECT_NE(message("constraints: {rod_travel: [0.2, 0.1]}\n").find("rod_travel"), std::string::npos);
  EXPECT_NE(message("near_ground_radius: -1\n").find("near_ground_radius"), std::string::npos);
  // A rod travel no mirror fits: the error names the member.
  DesignConfig cfg = ParseDesignConfig(
      base + "constraints: {rod_travel: [0.30, 0.31]}\nfamily: [{name: tall, objective: widest_field}]\n", "t.yaml");
  cfg.sweep = {21, 21, 1};
  try {
    RunFamilyStudy(cfg);
    ADD_FAILURE() << "an impossible rod travel was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("family mirror 'tall'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hovs::design
