// Sub-pixel edges of printed targets measured along their length, shared by the checkerboard corners
// (calib/checkerboard_edges.h) and the ArUco marker corners (depth/marker_edges.h).
//
// A straight printed edge is a curve in a catadioptric image. It is measured at one-pixel steps along its
// length: a short intensity profile across it gives the edge position as the area of its dark fraction between
// the dark and the bright level (preserved by any symmetric blur and by the pixels' own integration, unlike a
// threshold crossing, which locks towards pixel centres by up to 0.08 px), the profile taken as flat beyond the
// first sample back at either level. The positions are fitted by a polynomial offset from a chord (quadratic;
// cubic only where clearly better), measured again centred on the fit with the median levels, cleaned of
// outliers and fitted again. Corners are where two fitted edges meet. No camera model is needed.
//
// Pixel convention: (u, v) = (column, row), the centre of the top-left pixel at (0, 0), as in the core.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/types.h"

namespace hovs::calib {

// Bilinear grey value of an 8-bit grey image at (u, v); nullopt outside the image.
std::optional<double> SampleGrey(const cv::Mat& grey, double u, double v);

// A fitted edge: point(t) = p + t e + f(t) n, with f a polynomial in s = t / len - 0.5 (t in pixels along the
// chord from p, e the chord's unit direction, n its normal).
struct EdgeCurve {
  Vec2d p = Vec2d::Zero(), e = Vec2d::UnitX(), n = Vec2d::UnitY();
  double len = 1;
  Eigen::VectorXd coef;  // f(s) = sum coef[k] s^k
  double fit_rms = 0;    // px, of the kept edge points about the fit
  int points = 0;        // edge points kept
  double Offset(double t) const;
  double Slope(double t) const;  // df/dt
  Vec2d At(double t) const { return p + t * e + Offset(t) * n; }
  Vec2d Tangent(double t) const { return e + Slope(t) * n; }
};

// A stretch of the chord to measure: t from `from` to `to` (either direction; tracked from `from`, where the
// edge is expected on the chord), with the dark side on -n (dark_on_minus_n) or on +n.
struct EdgeStretch {
  double from = 0, to = 0;
  bool dark_on_minus_n = true;
};

struct EdgeCurveOptions {
  double half_profile = 2;       // px: the profile reaches this far to either side of the predicted edge
  double min_contrast = 20;      // grey levels between the dark and the bright level
  double max_fit_rms_px = 0.35;  // an edge whose points scatter more is not used
  double min_coverage = 0.6;     // fraction of the stretches' one-pixel steps that must give an edge point
};

// Measures an edge along the chord (p, e, len; n = e rotated by +90 degrees) over the given stretches and
// fits it. nullopt when too few points were found, the contrast is too low or the points scatter too much.
std::optional<EdgeCurve> MeasureEdgeCurve(const cv::Mat& grey, const Vec2d& p, const Vec2d& e, double len,
                                          const std::vector<EdgeStretch>& stretches, const EdgeCurveOptions& options);

// Where curves a and b meet, by Newton's method from the parameters ta0 on a and tb0 on b; nullopt for (nearly)
// parallel curves or a meeting point more than half a chord length from where it was sought.
std::optional<Vec2d> IntersectEdgeCurves(const EdgeCurve& a, double ta0, const EdgeCurve& b, double tb0);

}  // namespace hovs::calib
