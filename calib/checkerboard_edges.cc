#include "calib/checkerboard_edges.h"

#include <algorithm>
#include <cmath>

#include "calib/edge_curve.h"

namespace hovs::calib {
namespace {

// Is the image darker on the +n side of the chord than on the -n side around the point q?
std::optional<bool> DarkOnPlusN(const cv::Mat& g, const Vec2d& q, const Vec2d& n, double d) {
  const auto plus = SampleGrey(g, q.x() + d * n.x(), q.y() + d * n.y());
  const auto minus = SampleGrey(g, q.x() - d * n.x(), q.y() - d * n.y());
  if (!plus || !minus) return std::nullopt;
  return *plus < *minus;
}

// The board line through corner c along one grid direction, between its neighbours prev and next (either may
// be missing: the line then continues over the board's outer square, measured to 0.8 of a square).
std::optional<EdgeCurve> MeasureLine(const cv::Mat& g, const Vec2d& c, const std::optional<Vec2d>& prev,
                                     const std::optional<Vec2d>& next, double across, const CheckerboardEdgeOptions& o,
                                     double* t_corner) {
  if (!prev && !next) return std::nullopt;
  const Vec2d e = prev && next ? (*next - *prev).normalized()
                  : next       ? (*next - c).normalized()
                               : (c - *prev).normalized();
  const Vec2d n(-e.y(), e.x());
  double lm = prev ? (c - *prev).dot(e) : 0, lp = next ? (*next - c).dot(e) : 0;
  if (!prev) lm = 0.8 * lp;
  if (!next) lp = 0.8 * lm;
  const double square = std::min(prev ? lm : lp, next ? lp : lm);
  if (!(square >= o.min_square_px) || !(across >= o.min_square_px)) return std::nullopt;
  // Clear of the crossing line at the corner and at the neighbours (their blur and the pixel's own size).
  const double end = std::max(2.0, 0.2 * square);
  if (lm - (prev ? 2 : 1) * end < 3 || lp - (next ? 2 : 1) * end < 3) return std::nullopt;
  // The dark side on each half of the line (it swaps at the corner).
  const double probe = std::clamp(0.3 * across, 1.5, 6.0);
  const auto before = DarkOnPlusN(g, c - 0.5 * lm * e, n, probe);
  const auto after = DarkOnPlusN(g, c + 0.5 * lp * e, n, probe);
  if (!before || !after || *before == *after) return std::nullopt;
  EdgeCurveOptions eo;
  eo.half_profile = std::clamp(0.45 * across, 1.0, 4.0);
  eo.min_contrast = o.min_contrast;
  eo.max_fit_rms_px = o.max_fit_rms_px;
  const Vec2d p = c - lm * e;
  *t_corner = lm;
  return MeasureEdgeCurve(g, p, e, lm + lp,
                          {{lm - end, prev ? end : 0.0, !*before}, {lm + end, lm + lp - (next ? end : 0.0), !*after}},
                          eo);
}

}  // namespace

std::vector<bool> RefineCheckerboardCornersByEdges(const cv::Mat& grey, int cols, int rows,
                                                   std::vector<std::optional<Vec2d>>* grid,
                                                   const CheckerboardEdgeOptions& o) {
  const size_t total = static_cast<size_t>(cols) * rows;
  std::vector<bool> refined(total, false);
  if (grey.empty() || grey.type() != CV_8UC1 || grid->size() != total) return refined;
  const std::vector<std::optional<Vec2d>> start = *grid;
  std::vector<std::optional<Vec2d>> cur = start;
  const auto at = [&](const std::vector<std::optional<Vec2d>>& gr, int i, int j) -> std::optional<Vec2d> {
    if (i < 0 || j < 0 || i >= cols || j >= rows) return std::nullopt;
    return gr[static_cast<size_t>(j) * cols + i];
  };
  // Distance to the nearest neighbour along a grid direction (the square's size across the other line).
  const auto spacing = [&](const std::vector<std::optional<Vec2d>>& gr, int i, int j, int di, int dj) {
    double s = HUGE_VAL;
    const Vec2d c = *at(gr, i, j);
    for (int k : {-1, 1})
      if (const auto q = at(gr, i + k * di, j + k * dj)) s = std::min(s, (*q - c).norm());
    return s;
  };
  std::vector<double> last_move(total, HUGE_VAL);
  for (int pass = 0; pass < o.max_passes; ++pass) {
    std::vector<std::optional<Vec2d>> next = cur;
    double worst = 0;
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        const size_t k = static_cast<size_t>(j) * cols + i;
        if (!cur[k]) continue;
        const Vec2d c = *cur[k];
        double ta = 0, tb = 0;
        const auto row = MeasureLine(grey, c, at(cur, i - 1, j), at(cur, i + 1, j), spacing(cur, i, j, 0, 1), o, &ta);
        if (!row) continue;
        const auto col = MeasureLine(grey, c, at(cur, i, j - 1), at(cur, i, j + 1), spacing(cur, i, j, 1, 0), o, &tb);
        if (!col) continue;
        const auto q = IntersectEdgeCurves(*row, ta, *col, tb);
        if (!q || (*q - *start[k]).norm() > o.max_shift_px) continue;
        last_move[k] = (*q - c).norm();
        worst = std::max(worst, last_move[k]);
        next[k] = *q;
        refined[k] = true;
      }
    cur = next;
    if (worst < o.settled_px) break;
  }
  for (size_t k = 0; k < total; ++k) {
    if (refined[k] && last_move[k] > o.unsettled_px) refined[k] = false;
    (*grid)[k] = refined[k] ? cur[k] : start[k];
  }
  return refined;
}

}  // namespace hovs::calib
