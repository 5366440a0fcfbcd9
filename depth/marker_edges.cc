#include "depth/marker_edges.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "calib/edge_curve.h"

namespace hovs::depth {
namespace {

using calib::EdgeCurve;

// Measures the side from a to b (the marker's centroid c tells inside from outside).
// across: the cell size across the side (the adjacent sides' length / cells; near the rim the mirror squeezes
// cells radially, so it can be much less than along the side).
std::optional<EdgeCurve> MeasureSide(const cv::Mat& g, const Vec2d& a, const Vec2d& b, const Vec2d& c, double across,
                                     const MarkerEdgeOptions& o) {
  const double len = (b - a).norm();
  const double cell = len / o.cells;
  if (!(cell >= o.min_cell_px) || !(across >= o.min_cell_px)) return std::nullopt;
  const Vec2d e = (b - a) / len, n(-e.y(), e.x());
  calib::EdgeCurveOptions eo;
  eo.half_profile = std::clamp(0.45 * across, 1.0, 4.0);
  eo.min_contrast = o.min_contrast;
  eo.max_fit_rms_px = o.max_fit_rms_px;
  // Clear of the adjacent sides' edges (blur and the pixel); the marker's dark border is inside.
  const double end = std::max(2.0, 0.25 * cell);
  if (len - 2 * end < 5) return std::nullopt;
  return calib::MeasureEdgeCurve(g, a, e, len, {{end, len - end, n.dot(c - 0.5 * (a + b)) <= 0}}, eo);
}

}  // namespace

std::array<bool, 4> RefineMarkerCornersByEdges(const cv::Mat& grey, std::array<Vec2d, 4>* corners,
                                               const MarkerEdgeOptions& o) {
  std::array<bool, 4> refined{false, false, false, false};
  if (grey.empty() || grey.type() != CV_8UC1) return refined;
  const auto& c = *corners;
  const Vec2d centroid = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  std::array<std::optional<EdgeCurve>, 4> sides;  // side k: corner k -> corner k + 1
  for (int k = 0; k < 4; ++k) {
    const double across = 0.5 * ((c[(k + 1) % 4] - c[(k + 2) % 4]).norm() + (c[(k + 3) % 4] - c[k]).norm()) / o.cells;
    sides[k] = MeasureSide(grey, c[k], c[(k + 1) % 4], centroid, across, o);
  }
  std::array<Vec2d, 4> out = c;
  for (int k = 0; k < 4; ++k) {
    const auto& a = sides[(k + 3) % 4];  // ends at corner k
    const auto& b = sides[k];            // starts at corner k
    if (!a || !b) continue;
    const auto p = calib::IntersectEdgeCurves(*a, a->len, *b, 0);
    if (!p) continue;
    out[k] = *p;
    refined[k] = true;
  }
  *corners = out;
  return refined;
}

}  // namespace hovs::depth
