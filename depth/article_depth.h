// The article's closed-form binocular depth (section 3.1, equations 4-10) beside hovs' triangulation, and a
// study of what the closed form costs on a real (slightly misaligned) rig.
//
// The article assumes both units upright, their frames parallel and the baseline b along their x axes. With
// phi_1, phi_2 the azimuths of a point at the left and right unit (from x, the direction from left to right) the
// law of sines in the horizontal triangle gives the horizontal range from the left viewpoint
//   r_1 = b sin(phi_2) / sin(phi_2 - phi_1)
// and the height from the left unit's elevation of the point: z_1 = r_1 tan(el_1). hovs' Triangulate
// (depth/stereo.h) intersects the two rays with the rig's full relative pose instead.
#pragma once

#include <string>
#include <vector>

#include "core/statistics.h"
#include "depth/stereo.h"

namespace hovs::depth {

struct ClosedFormDepth {
  bool ok = false;
  Vec3d point_left = Vec3d::Zero();  // left mirror frame
};

// Bearings in each unit's own mirror frame. Fails where the two azimuths are (nearly) equal: the point lies on
// the baseline's line or at infinity.
ClosedFormDepth ArticleClosedForm(double baseline, const Vec3d& bearing_left, const Vec3d& bearing_right);

struct DepthFormulaOptions {
  std::vector<double> ranges_m = {1, 2, 5, 10, 20};          // from the left viewpoint
  std::vector<double> elevations_deg = {-5, -15, -30, -45};  // in the left mirror frame
  double azimuth_step_deg = 5;                               // all round, from the baseline's direction
  double min_angle_to_baseline_deg = 10;
  void Check(const std::string& where) const;
};

// Relative 3-D error |estimate - truth| / range of each method, per bin.
struct DepthFormulaBin {
  std::string name;
  std::vector<SampleSummary> methods;  // in DepthFormulaStudy::methods' order
};

struct DepthFormulaStudy {
  std::vector<std::string> methods;
  std::vector<DepthFormulaBin> by_range, by_angle;
  size_t points = 0;
};

// Points all round the left unit, seen by both units of `rig` (the exact models of the rig: each point projected
// to its pixels, then back to bearings), located by
//   - the article's closed form on each unit's own bearings (the frames taken as parallel),
//   - the closed form on bearings turned into the left unit's orientation (the rig's rotation known from
//     calibration, its offsets from the baseline ignored),
//   - hovs' triangulation of the bearings from each viewpoint F1 with the rig's full pose,
//   - hovs' triangulation of each unit's own rays (off F1 for a unit that is not single-viewpoint).
// Throws hovs::Error when no point is seen by both units.
DepthFormulaStudy CompareDepthFormulas(const StereoRig& rig, const DepthFormulaOptions& options = {});

// The two tables (by range, by angle to the baseline) in Markdown: median and 95th percentile per method.
std::string DepthFormulaMarkdown(const DepthFormulaStudy& study);

}  // namespace hovs::depth
