// Checkerboard corners in catadioptric images, where cv::findChessboardCorners fails: the board is bent into an
// arc, its squares shrink by a factor of several from one end to the other and it may be cut by the mirror rim or
// the camera's own reflection.
//
// Method (in the original image, so no resampling touches the corners):
//  1. Saddle candidates: the scale-normalised Hessian determinant -(Ixx Iyy - Ixy^2) at two scales, local maxima.
//  2. Each candidate is refined (cv::cornerSubPix) and verified on a circle around it: exactly four
//     bright/dark transitions, enough contrast, opposite transitions about 180 degrees apart (two edge lines
//     cross there). The two edge directions and the polarity are kept.
//  3. A grid grows from seed candidates: neighbours are found along the edge lines (adjacent corners share an
//     edge, so the line joining them is an edge direction of both, and their polarity alternates); whole rows and
//     columns are added while every new corner is found near its position extrapolated (quadratically) from the
//     two or three corners before it, which follows the mirror's distortion (or, where that finds none, linearly
//     from the two before it: the quadratic extrapolation multiplies the candidates' own error up to seven
//     times, too much on squares of about 15 px). The largest grid wins.
//  4. The grid is labelled against the board: its axes are matched to the board's, and its handedness is fixed by
//     the expected orientation in the image (one mirror reflection mirrors the board; the sign is an option).
//     Partial grids are labelled from their own first corner: for monocular calibration, where each image has its
//     own pose, that is exact. Grids larger than the board are refused (the board does not match the image).
//  5. Sub-pixel refinement (cv::cornerSubPix) with a window scaled to the local square size, then (by default)
//     each corner where the two board lines through it, measured along their length, cross
//     (calib/checkerboard_edges.h).
//  6. The labels are proved: each corner must lie where its row and its column put it (predicted from its
//     neighbours on both lines); corners off by more than a fraction of the local square are removed, and a
//     grid that loses more than a fifth of its corners is refused, with the reason in the status.
// An optional validity predicate (from a prior model: outside the rim, the camera's reflection) drops candidates.
// Every image gets a status: what was found, or why nothing was.
#pragma once

#include <functional>
#include <opencv2/core.hpp>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calib/polynomial_calibration.h"
#include "core/types.h"

namespace hovs::calib {

struct CheckerboardSpec {
  int cols = 7;          // inner corners along the board's x axis
  int rows = 5;          // inner corners along y
  double square = 0.03;  // metres
  void Check(const std::string& where) const;
};

// A ChArUco board (OpenCV's): squares_x x squares_y squares, the top-left one (as printed) black, an ArUco
// marker of side `marker` in every white square. Its inner corners are named by the markers around them, so a
// partial view near the rim keeps certain labels. Corner id = row * (squares_x - 1) + column (OpenCV's), from the
// top-left inner corner as printed; in hovs' board frame (x right, y up the print, z out of it, origin at the
// pattern's centre) corner (column c, row r) is at ((c + 1) square - W / 2, H / 2 - (r + 1) square).
struct CharucoSpec {
  int squares_x = 8, squares_y = 6;
  double square = 0.03, marker = 0.022;  // metres
  std::string dictionary = "DICT_4X4_250";
  void Check(const std::string& where) const;
  int Cols() const { return squares_x - 1; }  // inner corners
  int Rows() const { return squares_y - 1; }
  Vec2d CornerXY(int id) const;  // board frame, metres
};

// "charuco:SXxSYxSQUARExMARKER[:DICTIONARY]" (squares, square and marker sides in metres), e.g.
// charuco:8x6x0.03x0.022:DICT_4X4_250. Throws naming `where`.
CharucoSpec ParseCharucoSpec(const std::string& text, const std::string& where);

struct CheckerboardDetectOptions {
  CheckerboardSpec board;
  std::optional<CharucoSpec> charuco;  // set: the board is this ChArUco board (DetectCharuco)
  int min_corners = 12;                // smaller grids are not reported as found
  bool allow_partial = true;           // false: only the complete board counts as found
  // Expected sign of cross(x axis, y axis) of the board in the image ((u, v) pixels): -1 for a board seen through
  // one mirror reflection from its printed side (catadioptric cameras), +1 for a direct view.
  int orientation = -1;
  double min_contrast = 0.06;  // bright minus dark on the verification circle, in [0, 1] grey
  int max_seeds = 60;          // seed candidates tried (strongest first)
  int subpix_half_window = 0;  // cv::cornerSubPix half window; 0: 0.35 x the local square size, in [2, 11]
  // "edges": after cornerSubPix, each corner where the two board lines measured along their length cross
  // (calib/checkerboard_edges.h); "subpix": cornerSubPix alone.
  std::string corner_refinement = "edges";
  std::function<bool(const Vec2d&)> valid;  // optional: pixels where the board can be seen (prior model)
  // Labels proved at detection: a corner further than this fraction of the local square from where its row and
  // column put it is removed; a grid losing more than a fifth of its corners is refused.
  double max_label_error = 0.25;
  void Check(const std::string& where) const;
};

struct CheckerboardDetection {
  bool found = false;
  bool complete = false;  // every inner corner of the board
  std::string status;     // e.g. "complete 7x5", "partial 5x4 (20 of 35)", "no grid: 3 saddle candidates"
  int candidates = 0;     // verified saddle points in the image
  int grid_cols = 0, grid_rows = 0;
  std::vector<Vec2d> pixels;             // refined corners (u, v)
  int from_edges = 0;                    // corners refined from the board's edges (the others: cornerSubPix)
  int rejected = 0;                      // corners removed by the label check
  std::string rejected_reason;           // e.g. "2 off their row or column (up to 0.61 of a square)"
  double worst_label_error = 0;          // largest row/column error among the kept corners (fraction of a square)
  std::vector<Vec3d> board_points;       // board frame, metres, z = 0
  std::vector<Eigen::Vector2i> indices;  // (column, row) on the board
};

// image: 8-bit grey (CV_8UC1). Throws hovs::Error for an empty or non-grey image or bad options.
CheckerboardDetection DetectCheckerboard(const cv::Mat& image, const CheckerboardDetectOptions& options);

// A ChArUco board: its ArUco markers (in the image and in its mirror image, whichever shows more: one mirror
// reflection mirrors the board), the inner corners between them interpolated by OpenCV (local homographies of
// the nearest markers, then cv::cornerSubPix), then (corner_refinement "edges") each corner where the board's
// lines through it cross, as for a checkerboard. Uses options.charuco, min_corners, corner_refinement and
// min_contrast. board_points in hovs' board frame (CharucoSpec), indices (column, row).
CheckerboardDetection DetectCharuco(const cv::Mat& image, const CheckerboardDetectOptions& options);

// The labels' proof: every corner must lie where its row and its column put it. Along each grid line through a
// corner its position is predicted from the neighbours on that line (cubic through two on each side, else the
// midpoint of one on each side, else quadratic extrapolation from three on one side); its error is the smaller
// of the two lines' predictions, relative to the local square. A corner off by more than max_fraction of the
// square (at least min_px) is not on its row or column: a wrong candidate or a mislabelled corner. The worst such
// corner is removed and the others re-checked without it (a wrong corner spoils its neighbours' predictions).
// Returns, per corner, whether it is kept; *worst is the largest relative error among the kept corners.
std::vector<char> ProveGridLabels(const std::vector<Vec2d>& pixels, int cols, int rows, double max_fraction,
                                  double min_px, std::vector<double>* removed_errors, double* worst);

// Convenience: a detection as a calibration observation.
BoardObservation ToObservation(const CheckerboardDetection& detection, const std::string& image_name);

// Versions of the libraries calibration uses beside the core's: "opencv" (the one loaded; detection, ArUco,
// the omnidir comparison).
std::map<std::string, std::string> CalibVersions();

}  // namespace hovs::calib
