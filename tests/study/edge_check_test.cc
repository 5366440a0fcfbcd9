// The blur prediction against the renderer: slanted edges rendered through the thin lens agree with the MTF50 the
// exact spot predicts, over sharp and blurred field points, in both directions.
#include <gtest/gtest.h>

#include "study/edge_check.h"

namespace hovs::study {
namespace {

TEST(EdgeCheck, RenderedEdgesAgreeWithThePredictedMtf50) {
  EdgeCheckOptions o;
  o.camera.lens.f_number = 8;
  o.camera.lens.focus_distance = 0.1539;  // about the best single focus of 48/44 over 1 m .. infinity
  o.elevations_deg = {-70, -40, -15};
  o.distances = {1.0, 30.0};
  o.samples = 256;
  const EdgeCheck c = RunEdgeCheck(o);
  ASSERT_EQ(c.results.size(), 12u);
  bool blurred = false, sharp = false;
  for (const EdgeResult& r : c.results) {
    EXPECT_TRUE(r.ok) << r.elevation_deg << " deg, " << r.distance << " m, " << r.direction << ": predicted "
                      << r.predicted_mtf50 << ", measured " << r.measured_mtf50 << " " << r.note;
    blurred |= r.predicted_rms > 1.0, sharp |= r.predicted_rms < 0.5;
  }
  EXPECT_TRUE(blurred && sharp) << "the grid should hold both sharp and blurred points";
}

TEST(EdgeCheck, RefusesOptionsItCannotMeasureWith) {
  EdgeCheckOptions o;
  o.samples = 4;
  EXPECT_THROW(RunEdgeCheck(o), Error);
  o = EdgeCheckOptions{};
  o.region = 8;
  EXPECT_THROW(RunEdgeCheck(o), Error);
  o = EdgeCheckOptions{};
  o.camera.lens.f_number = -1;
  EXPECT_THROW(RunEdgeCheck(o), Error);
  o = EdgeCheckOptions{};
  o.elevations_deg = {10};  // above the field (which ends below the horizon)
  try {
    RunEdgeCheck(o);
    ADD_FAILURE() << "an elevation outside the field was accepted";
  } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("outside the design's field"), std::string::npos); }
}

}  // namespace
}  // namespace hovs::study
