// Focus and depth of field of a catadioptric design (definitions in optics/README.md): through-focus curves,
// the best focus of each field point (radial, tangential and RMS), the single focus that minimises the worst RMS
// blur over a field band and a distance range, the depth of field per elevation for a blur limit, and the blur
// atlas (elevation x distance at one focus). Focus distances are object side, from the lens; +inf allowed.
// Searches run in the lens's vergence 1 / d (0 at infinity), where the blur of a point is smooth.
#pragma once

#include <limits>
#include <vector>

#include "optics/blur.h"

namespace hovs::optics {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A field point's bundle traced once (refocused analytically by BlurOf).
struct TracedField {
  FieldPoint field;
  Bundle bundle;
};
std::vector<TracedField> TraceFields(const OpticalSystem& sys, const std::vector<FieldPoint>& fields);

struct FocusSample {
  double focus_distance = 0, rms = 0, radial_rms = 0, tangential_rms = 0;
};
// The spot's RMS sizes at each focus distance.
std::vector<FocusSample> ThroughFocus(const OpticalSystem& sys, const Bundle& b, const std::vector<double>& focus);

// The focus distances (within [min_focus, inf]) that minimise a field point's RMS radius, its radial RMS and its
// tangential RMS: the best-focus surface and its two astigmatic sheets.
struct BestFocus {
  double rms_focus = kInfinity, radial_focus = kInfinity, tangential_focus = kInfinity;
  double rms = 0;  // the RMS radius at rms_focus, px
};
BestFocus BestFocusOf(const OpticalSystem& sys, const Bundle& b, double min_focus);

// The single focus in [min_focus, inf] that minimises the largest RMS radius over `fields` (their bundles);
// worst: that largest RMS radius; worst_field: where it is.
struct SingleFocus {
  double focus_distance = kInfinity, worst_rms = 0;
  size_t worst_field = 0;
};
SingleFocus BestSingleFocus(const OpticalSystem& sys, const std::vector<TracedField>& fields, double min_focus);

// The depth of focus of a design about its best single focus: the focus settings (object side, from the lens)
// whose worst RMS radius over `fields` stays within tolerance_px of the best single focus's worst_rms. near_focus
// is the closest such setting (>= min_focus), far_focus the farthest (+inf when focusing at infinity stays within).
struct DepthOfFocus {
  double best_focus = kInfinity, near_focus = kInfinity, far_focus = kInfinity;
  double best_worst_rms = 0, tolerance_px = 0;
  bool Contains(double focus) const { return focus >= near_focus && focus <= far_focus; }
};
DepthOfFocus DepthOfFocusOf(const OpticalSystem& sys, const std::vector<TracedField>& fields, const SingleFocus& best,
                            double tolerance_px, double min_focus);

// The near and far sharp limits (distance from F1, m) of an elevation at one focus: the range about the sharpest
// distance in [min_distance, inf] whose RMS radius stays <= limit_px. far is +inf when sharp out to infinity;
// sharp is false (and near, far are NaN) when no distance is.
struct DepthOfField {
  double elevation_deg = 0, near = 0, far = 0;
  bool sharp = false;
};
DepthOfField DepthOfFieldAt(const OpticalSystem& sys, double elevation_deg, double focus_distance, double limit_px,
                            double min_distance);

// The field points of a band: n_elevation elevations evenly inside [lower_deg, upper_deg] (half a step from each
// end) times the distances, at azimuth 0.
std::vector<FieldPoint> FieldGrid(double lower_deg, double upper_deg, int n_elevation,
                                  const std::vector<double>& distances);
// n distances from near to far, log-spaced, the last one +inf (n >= 2).
std::vector<double> DistanceGrid(double near, double far, int n);

// The blur of every field point at one focus (TBB over the points).
std::vector<FieldBlur> Atlas(const OpticalSystem& sys, const std::vector<FieldPoint>& fields, double focus_distance);

}  // namespace hovs::optics
