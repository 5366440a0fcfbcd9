// Sub-pixel checkerboard corners from the board's edges.
//
// cv::cornerSubPix finds the point where the image gradients in a small window are orthogonal to the
// direction towards it: a few dozen pixels decide, and in a catadioptric image the window also sees the
// curvature of the edges and the neighbouring corners once a square is only 10-20 px wide. Here each inner
// corner is where the two board lines through it cross, and each line is measured along its whole length on
// both sides of the corner, up to the neighbouring corners (calib/edge_curve.h: area-of-step edge positions at
// one-pixel steps, fitted by a polynomial offset that follows the mirror's bending): the corner is
// interpolated between some 20-60 edge points instead of found in a window. The dark side swaps at the corner,
// which the measurement follows. Repeated from its own result until the corners settle; a corner whose lines
// could not be measured (the board's border, low contrast, occlusion) or that did not settle keeps its
// previous position.
#pragma once

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "core/types.h"

namespace hovs::calib {

struct CheckerboardEdgeOptions {
  double min_contrast = 20;      // grey levels between dark and bright squares
  double max_fit_rms_px = 0.35;  // a line whose edge points scatter more is not used
  double min_square_px = 5;      // smaller squares keep their corners as they were
  double max_shift_px = 1.5;     // a refined corner further than this from its start is not trusted
  int max_passes = 4;
  double settled_px = 0.02;   // a pass that moves no corner more than this ends the refinement
  double unsettled_px = 0.1;  // a corner still moving this much in the last pass keeps its start
};

// grey: 8-bit grey image. grid: cols x rows inner corners, corner (column i, row j) at grid[j * cols + i],
// nullopt where not found; refined in place. Returns, per corner, whether it was refined from the edges.
std::vector<bool> RefineCheckerboardCornersByEdges(const cv::Mat& grey, int cols, int rows,
                                                   std::vector<std::optional<Vec2d>>* grid,
                                                   const CheckerboardEdgeOptions& options = {});

}  // namespace hovs::calib
