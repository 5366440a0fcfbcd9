// Sub-pixel marker corners from the marker's edges.
//
// A square marker's outer corner is an L-junction, not a saddle: a corner detector's window (cornerSubPix)
// also sees the edges of the marker's inner bits once a bit cell is only a few pixels wide, and is pulled
// towards them. The marker's four sides, however, are long straight edges in the scene. Here each side is
// measured along its whole length (one cell kept clear of each end): at about one-pixel steps a short
// intensity profile across the side gives the sub-pixel position where it crosses half-way between the dark
// border and the bright surround (unbiased for a symmetric blur), the positions are fitted by a polynomial
// offset from the side's chord (cubic with enough samples: the catadioptric image bends straight lines), one
// round of outlier rejection, and each corner is the intersection of its two fitted sides. Everything happens
// in the image itself, so it needs no camera model and works with any calibration (or none).
//
// Pixel convention: (u, v) = (column, row), the centre of the top-left pixel at (0, 0), as in the core.
#pragma once

#include <array>

#include <opencv2/core.hpp>

#include "core/types.h"

namespace hovs::depth {

struct MarkerEdgeOptions {
  int cells = 8;                  // cells across the marker (bits + 2 for the black border), e.g. 8 for 6 x 6
  double min_cell_px = 2.5;       // smaller markers keep their corners as they were
  double min_contrast = 20;       // grey levels between the dark border and the surround
  double max_fit_rms_px = 0.35;   // a side whose edge points scatter more is not used
};

// corners: the marker's four corners (any consistent order around the marker) in the 8-bit grey image;
// refined in place where both sides of a corner measured well. Returns which corners were refined.
std::array<bool, 4> RefineMarkerCornersByEdges(const cv::Mat& grey, std::array<Vec2d, 4>* corners,
                                               const MarkerEdgeOptions& options);

}  // namespace hovs::depth
