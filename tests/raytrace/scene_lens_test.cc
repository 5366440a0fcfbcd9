// A scene unit's lens (camera.lens, core/lens.h): its image scale follows the focus, the renderer defocuses through
// it exactly as through the same aperture and focus given as render options, and bad lenses are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.h"
#include "raytrace/render.h"
#include "scenes/scene_config.h"

namespace hovs {
namespace {

std::string Scene(const std::string& lens, const std::string& render = "render: {samples: 4, seed: 3}\n") {
  return "units:\n  - mirror: {a: 0.048, b: 0.044, rim_diameter: 0.080}\n"
         "    camera: {focal_length: 0.016, pixel_pitch: 4.54e-5, width: 275, height: 220, lens_aperture: 0.020" +
         (lens.empty() ? "" : ", lens: " + lens) +
         "}\n"
         "    pose: {position: [0, 0, 1.3]}\n"
         "objects:\n  - {type: ground, name: floor, texture: {checker: {squares: [40, 40], square: 0.1}}}\n" +
         render;
}

TEST(SceneLens, TheImageScaleIsTheSensorDistanceAtTheFocus) {
  const double f = 0.016, d = 0.1537, pitch = 4.54e-5;
  const auto focused = scenes::ParseSceneConfig(Scene("{f_number: 4, focus_distance: 0.1537}"), "lens.yaml", ".");
  const raytrace::CatadioptricUnit& u = focused.description.units.at(0);
  ASSERT_TRUE(u.lens.has_value());
  EXPECT_DOUBLE_EQ(u.lens->f_number, 4);
  EXPECT_NEAR(u.rig.camera.fx, f * d / (d - f) / pitch, 1e-9);
  EXPECT_NEAR(u.rig.camera.fy, u.rig.camera.fx, 1e-12);
  // Focused at infinity the scale is f; without a lens the unit is a pinhole of scale f.
  const auto far = scenes::ParseSceneConfig(Scene("{f_number: 8}"), "lens.yaml", ".");
  EXPECT_NEAR(far.description.units[0].rig.camera.fx, f / pitch, 1e-9);
  const auto pinhole = scenes::ParseSceneConfig(Scene(""), "lens.yaml", ".");
  EXPECT_FALSE(pinhole.description.units[0].lens.has_value());
  EXPECT_NEAR(pinhole.description.units[0].rig.camera.fx, f / pitch, 1e-9);
}

TEST(SceneLens, TheUnitsLensRendersAsTheSameApertureAndFocusGivenAsOptions) {
  const auto cfg = scenes::ParseSceneConfig(Scene("{f_number: 4, focus_distance: 0.1537}"), "lens.yaml", ".");
  const raytrace::RayScene scene(cfg.description);
  raytrace::RenderOptions ro = cfg.render;
  ro.ground_truth = false;
  const raytrace::Frame through_lens = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  raytrace::RenderOptions explicit_lens = ro;
  explicit_lens.lens_radius = 0.016 / 4 / 2, explicit_lens.focus_distance = 0.1537;
  const raytrace::Frame as_options = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), explicit_lens);
  ASSERT_EQ(through_lens.rgb.size(), as_options.rgb.size());
  EXPECT_EQ(through_lens.rgb, as_options.rgb);
  // A pinhole render of the same scene differs (the lens defocuses), and a lens focused at infinity renders
  // finite pixels (its rays of one pixel are parallel).
  raytrace::RayScene pinhole_scene(scenes::ParseSceneConfig(Scene(""), "lens.yaml", ".").description);
  EXPECT_NE(raytrace::Render(pinhole_scene, raytrace::ViewCamera::Unit(0), ro).rgb, through_lens.rgb);
  const raytrace::RayScene far(scenes::ParseSceneConfig(Scene("{f_number: 4}"), "lens.yaml", ".").description);
  const raytrace::Frame at_infinity = raytrace::Render(far, raytrace::ViewCamera::Unit(0), ro);
  double sum = 0;
  for (float v : at_infinity.rgb) {
    ASSERT_TRUE(std::isfinite(v));
    sum += v;
  }
  EXPECT_GT(sum, 0);
}

TEST(SceneLens, BadLensesAreRefusedNamingTheKey) {
  const auto expect = [](const std::string& text, const std::string& needle) {
    try {
      scenes::ParseSceneConfig(text, "bad.yaml", ".");
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("camera.lens"), std::string::npos) << e.what();
    }
  };
  expect(Scene("{f_number: 0}"), "f_number");
  expect(Scene("{f_number: .nan}"), "f_number");
  expect(Scene("{f_number: 4, focus_distance: 0.01}"), "beyond the focal length");
  expect(Scene("{f_number: 0.5}"), "wider than the lens face");
  expect(Scene("{f_number: 4, aperture_diameter: 0.004}"), "not both");
  expect(Scene("{f_stop: 4}"), "unknown key 'f_stop'");
  // The render options' own lens is not a second definition.
  expect(Scene("{f_number: 4}", "render: {lens_radius: 0.002}\n"), "lens_radius");
  expect(Scene("", "render: {focus_distance: 0.2}\n"), "focus_distance");
}

}  // namespace
}  // namespace hovs
