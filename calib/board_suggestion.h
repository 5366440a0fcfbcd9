// Where to hold the board next: candidate poses of the calibration board around the viewpoint (azimuths all
// round, elevations across the calibrated field, a few distances and tilts), each seen through the calibrated
// model (every corner inside the image and the calibrated annulus), scored by how much its corners would lower
// the projection uncertainty (calib/projection_uncertainty.h) averaged over the field. The candidate's corners add
// their information (J^T J / sigma^2, for the intrinsics and the new pose) to the solve's; the covariance with
// the new board is the pseudo-inverse of the sum (the solve's gauge freedom stays one). Chosen greedily: each next
// board is the best given the boards already suggested.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/projection_uncertainty.h"

namespace hovs::calib {

struct SuggestOptions {
  int count = 3;                    // boards to suggest
  std::vector<double> distances_m;  // empty: the calibration boards' median distance x 0.75, 1, 1.33
  void Check(const std::string& where) const;
};

struct BoardSuggestion {
  Rigid3d cam_from_board;  // of the board whose frame is the board points' (centred where the caller's is)
  double azimuth_deg = 0, elevation_deg = 0, distance_m = 0, tilt_deg = 0;
  Vec2d centre_px = Vec2d::Zero();  // where the board's centre appears
  std::vector<Vec2d> corners_px;    // every corner through the model
  double mean_px = 0;               // the field's mean 1-sigma uncertainty with this board and those before it
};

struct Suggestions {
  double mean_px_now = 0;  // the field's mean 1-sigma uncertainty (px at the map's range) of the solve as it is
  int candidates = 0;      // poses that the model sees whole
  std::vector<BoardSuggestion> boards;
  std::vector<Vec3d> board_points;  // the board the poses are for (corners_px in this order)
};

// `board_points`: one image's board (z = 0 in the board frame), as the calibration used it. `map`: the range and
// the annulus over which the uncertainty is averaged (its grid step is coarsened to about 24 columns). Throws
// hovs::Error when the covariance is missing or no candidate is seen whole.
Suggestions SuggestBoardPoses(const ParametricModel& model, const SolveCovariance& solve,
                              const std::vector<Vec3d>& board_points, const UncertaintyOptions& map,
                              const SuggestOptions& options);

nlohmann::json SuggestionsJson(const Suggestions& s);

}  // namespace hovs::calib
