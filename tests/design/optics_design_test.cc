// The blur constraint (constraints.max_blur_px) and the f-number as a design variable (lens.f_number: auto) on
// the article's 48 / 44 / 80 mirror with the 16 mm lens.
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "design/config.h"
#include "design/optics_report.h"

namespace hovs::design {
namespace {

std::string Config(const std::string& lens, const std::string& constraints) {
  return "camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.020}\n"
         "mirror: {rim_diameter: 0.080}\n"
         "lens: " +
         lens + "\nconstraints: " + constraints + "\n";
}

const DesignPoint kArticle{0.048, 0.044, 0.080};

TEST(DesignOptics, TheBlurConstraintIsJudgedOnTheAtlasAtTheFocus) {
  // f/4 cannot hold 1 px over 1 m .. infinity (about 5.6 px at the best single focus): NOT MET, and the f-number
  // that would is reported.
  const DesignConfig tight = ParseDesignConfig(Config("{f_number: 4}", "{max_blur_px: 1}"), "blur.yaml");
  const DesignOptics o = AnalyseOptics(kArticle, tight.problem, "article");
  ASSERT_TRUE(o.blur_constraint.has_value());
  EXPECT_EQ(o.blur_constraint->limit, 1.0);
  EXPECT_NEAR(o.blur_constraint->value, o.worst_rms - 1.0, 1e-12);
  EXPECT_GT(o.blur_constraint->value, 3.0);
  EXPECT_FALSE(o.f_number_auto);
  EXPECT_GT(o.f_number_for_limit, 8.0);
  EXPECT_NE(OpticsSummary(o, tight.problem).find("NOT MET"), std::string::npos);
  // Without the constraint there is nothing to judge.
  const DesignConfig none = ParseDesignConfig(Config("{f_number: 4}", "{rim_margin_px: 0}"), "blur.yaml");
  EXPECT_FALSE(AnalyseOptics(kArticle, none.problem, "article").blur_constraint.has_value());
}

TEST(DesignOptics, AnAutomaticFNumberIsTheWidestApertureThatMeetsTheConstraint) {
  const DesignConfig cfg = ParseDesignConfig(Config("{f_number: auto}", "{max_blur_px: 2}"), "blur.yaml");
  EXPECT_TRUE(cfg.problem.blur.auto_f_number);
  const DesignOptics o = AnalyseOptics(kArticle, cfg.problem, "article");
  EXPECT_TRUE(o.f_number_auto);
  ASSERT_TRUE(o.blur_constraint.has_value());
  EXPECT_LE(o.worst_rms, 2.0);  // met on the fine atlas, not only on the coarse search
  EXPECT_LE(o.blur_constraint->value, 0);
  // The widest such aperture: 10 % wider blurs past the limit.
  DesignProblem wider = cfg.problem;
  wider.blur.auto_f_number = false;
  wider.camera.lens.f_number = o.lens.f_number / 1.1;
  EXPECT_GT(AnalyseOptics(kArticle, wider, "article").worst_rms, 2.0);
  // The blur falls about as the aperture: between f/8 (2.75 px) and f/16 (1.37 px).
  EXPECT_GT(o.lens.f_number, 8.0);
  EXPECT_LT(o.lens.f_number, 16.0);
  EXPECT_NE(OpticsSummary(o, cfg.problem).find("chosen by the design"), std::string::npos);
}

TEST(DesignOptics, BadBlurConstraintsAreRefusedByName) {
  for (const std::string& bad :
       {std::string("{max_blur_px: 0}"), std::string("{max_blur_px: -1}"), std::string("{max_blur_px: .nan}")}) {
    try {
      ParseDesignConfig(Config("{f_number: 4}", bad), "blur.yaml");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("max_blur_px"), std::string::npos) << e.what(); }
  }
  EXPECT_THROW(ParseDesignConfig(Config("{f_number: automatic}", "{max_blur_px: 1}"), "blur.yaml"), Error);
}

}  // namespace
}  // namespace hovs::design
