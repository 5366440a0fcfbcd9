// Sub-pixel marker corners from the marker's edges.
//
// A square marker's outer corner is an L-junction, not a saddle: a corner detector's window (cornerSubPix)
// also sees the edges of the marker's inner bits once a bit cell is only a few pixels wide (and the board's
// edge for outer markers), and is pulled towards them. The marker's four sides, however, are long straight
// edges in the scene. Here each side is measured along its length (to within 2 px, or a quarter cell, of
// each corner) at one-pixel steps: a short intensity profile across the side gives the edge position as the
// area of its dark fraction between the dark border and the bright surround (preserved by any symmetric blur
// and by the pixels' own integration, unlike a threshold crossing), the profile taken as flat beyond the first
// sample back at either level. The positions are tracked along the side, fitted by a quadratic offset from
// the side's chord (cubic only where clearly better: the catadioptric image bends straight lines), measured
// again centred on the fit with the side's median levels, cleaned of outliers, and each corner is where its
// two fitted sides meet (the edge measurement is calib/edge_curve.h, shared with the checkerboard corners).
// Everything happens in the image itself: no camera model is needed, so it works with any calibration (or none).
//
// Pixel convention: (u, v) = (column, row), the centre of the top-left pixel at (0, 0), as in the core.
#pragma once

#include <array>

#include <opencv2/core.hpp>

#include "core/types.h"

namespace hovs::depth {

struct MarkerEdgeOptions {
  int cells = 8;                 // cells across the marker (bits + 2 for the black border), e.g. 8 for 6 x 6
  double min_cell_px = 2.5;      // smaller markers keep their corners as they were
  double min_contrast = 20;      // grey levels between the dark border and the surround
  double max_fit_rms_px = 0.35;  // a side whose edge points scatter more is not used
};

// corners: the marker's four corners (any consistent order around the marker) in the 8-bit grey image;
// refined in place where both sides of a corner measured well. Returns which corners were refined.
std::array<bool, 4> RefineMarkerCornersByEdges(const cv::Mat& grey, std::array<Vec2d, 4>* corners,
                                               const MarkerEdgeOptions& options);

}  // namespace hovs::depth
