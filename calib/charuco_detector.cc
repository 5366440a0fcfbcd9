// ChArUco boards: the spec, its parsing and the detector (calib/checkerboard_detector.h).
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "calib/aruco_dictionary.h"
#include "calib/checkerboard_detector.h"
#include "calib/checkerboard_edges.h"
#include "core/error.h"

namespace hovs::calib {

void CharucoSpec::Check(const std::string& where) const {
  HOVS_REQUIRE(squares_x >= 3 && squares_y >= 3 && squares_x <= 100 && squares_y <= 100, where,
               "a ChArUco board has 3 x 3 to 100 x 100 squares (got ", squares_x, " x ", squares_y, ")");
  HOVS_REQUIRE(std::isfinite(square) && square > 0 && square <= 10, where, "square size must be in (0, 10] m (got ",
               square, ")");
  HOVS_REQUIRE(std::isfinite(marker) && marker > 0 && marker < square, where,
               "the marker must be smaller than the square (got ", marker, " m in ", square, " m)");
  const int id = ArucoDictionaryId(dictionary, where);
  const int markers = squares_x * squares_y / 2;
  const int available = cv::aruco::getPredefinedDictionary(id)->bytesList.rows;
  HOVS_REQUIRE(markers <= available, where, "the board needs ", markers, " markers but ", dictionary, " has ",
               available);
}

Vec2d CharucoSpec::CornerXY(int id) const {
  const int c = id % Cols(), r = id / Cols();
  return Vec2d((c + 1) * square - 0.5 * squares_x * square, 0.5 * squares_y * square - (r + 1) * square);
}

CharucoSpec ParseCharucoSpec(const std::string& text, const std::string& where) {
  CharucoSpec s;
  char x1 = 0, x2 = 0, x3 = 0;
  int end = -1;
  const bool ok = text.rfind("charuco:", 0) == 0 &&
                  std::sscanf(text.c_str() + 8, "%d%c%d%c%lf%c%lf%n", &s.squares_x, &x1, &s.squares_y, &x2, &s.square,
                              &x3, &s.marker, &end) == 7 &&
                  x1 == 'x' && x2 == 'x' && x3 == 'x';
  HOVS_REQUIRE(ok, where,
               "expected charuco:SXxSYxSQUARExMARKER[:DICTIONARY] (squares, sides in metres), e.g. "
               "charuco:8x6x0.03x0.022 (got '",
               text, "')");
  const std::string rest = text.substr(8 + end);
  if (!rest.empty()) {
    HOVS_REQUIRE(rest[0] == ':' && rest.size() > 1, where, "expected :DICTIONARY after the sizes (got '", rest, "')");
    s.dictionary = rest.substr(1);
  }
  s.Check(where);
  return s;
}

namespace {

cv::Ptr<cv::aruco::CharucoBoard> MakeBoard(const CharucoSpec& s) {
  return cv::aruco::CharucoBoard::create(
      s.squares_x, s.squares_y, static_cast<float>(s.square), static_cast<float>(s.marker),
      cv::aruco::getPredefinedDictionary(ArucoDictionaryId(s.dictionary, "ChArUco board")));
}

struct Found {
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  int markers = 0;
};

// Markers and interpolated corners in `grey` (already mirrored or not by the caller).
Found Interpolate(const cv::Mat& grey, const cv::Ptr<cv::aruco::CharucoBoard>& board) {
  Found f;
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  auto params = cv::aruco::DetectorParameters::create();
  // Markers down to 12 px a side (OpenCV's default needs a perimeter of 3 % of the image's larger side: 21 px
  // markers in a 2750 px image, where the mirror shrinks a board near the inner radius below that).
  params->minMarkerPerimeterRate = std::min(params->minMarkerPerimeterRate, 48.0 / std::max(grey.cols, grey.rows));
  cv::aruco::detectMarkers(grey, board->dictionary, marker_corners, marker_ids, params);
  f.markers = static_cast<int>(marker_ids.size());
  if (marker_ids.empty()) return f;
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, grey, board, f.corners, f.ids, cv::noArray(),
                                       cv::noArray(), 2);
  return f;
}

}  // namespace

CheckerboardDetection DetectCharuco(const cv::Mat& image, const CheckerboardDetectOptions& o) {
  HOVS_REQUIRE(!image.empty() && image.type() == CV_8UC1, "charuco detection", "needs an 8-bit grey image");
  o.Check("charuco detection");
  HOVS_REQUIRE(o.charuco.has_value(), "charuco detection", "no ChArUco board given");
  const CharucoSpec& spec = *o.charuco;
  const auto board = MakeBoard(spec);
  // The image as it is and mirrored (a board seen through the mirror reads backwards): the one with more corners.
  cv::Mat mirrored;
  cv::flip(image, mirrored, 1);
  Found direct = Interpolate(image, board), flipped = Interpolate(mirrored, board);
  const bool use_flipped = flipped.ids.size() > direct.ids.size();
  Found& f = use_flipped ? flipped : direct;
  if (use_flipped)
    for (auto& p : f.corners) p.x = static_cast<float>(image.cols - 1) - p.x;
  CheckerboardDetection det;
  det.candidates = f.markers;
  det.grid_cols = spec.Cols(), det.grid_rows = spec.Rows();
  const int total = spec.Cols() * spec.Rows();
  std::vector<std::optional<Vec2d>> grid(total);
  for (size_t k = 0; k < f.ids.size(); ++k)
    if (f.ids[k] >= 0 && f.ids[k] < total) grid[f.ids[k]] = Vec2d(f.corners[k].x, f.corners[k].y);
  // OpenCV's interpolated corners sit about half a pixel off (its marker corners carry that bias into the local
  // homographies): each is found again by cv::cornerSubPix with a window that keeps clear of the markers (which
  // start (square - marker) / 2 from the corner: the half window is at most 0.8 of that, in pixels).
  const double clear = 0.8 * 0.5 * (spec.square - spec.marker) / spec.square;
  for (int id = 0; id < total; ++id) {
    if (!grid[id]) continue;
    double spacing = HUGE_VAL;
    const int c = id % spec.Cols(), r = id / spec.Cols();
    for (const auto& [dc, dr] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      const int cc = c + dc, rr = r + dr;
      if (cc < 0 || rr < 0 || cc >= spec.Cols() || rr >= spec.Rows() || !grid[rr * spec.Cols() + cc]) continue;
      spacing = std::min(spacing, (*grid[rr * spec.Cols() + cc] - *grid[id]).norm());
    }
    if (!std::isfinite(spacing)) continue;
    const int w = static_cast<int>(std::floor(clear * spacing));
    if (w < 2) continue;
    std::vector<cv::Point2f> one = {cv::Point2f(static_cast<float>(grid[id]->x()), static_cast<float>(grid[id]->y()))};
    cv::cornerSubPix(image, one, cv::Size(std::min(w, 11), std::min(w, 11)), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.001));
    const Vec2d q(one[0].x, one[0].y);
    if ((q - *grid[id]).norm() < 0.25 * spacing) grid[id] = q;
  }
  std::vector<bool> by_edges(total, false);
  if (o.corner_refinement == "edges") {
    CheckerboardEdgeOptions eo;
    eo.min_contrast = 255.0 * o.min_contrast;
    by_edges = RefineCheckerboardCornersByEdges(image, spec.Cols(), spec.Rows(), &grid, eo);
  }
  for (int id = 0; id < total; ++id) {
    if (!grid[id]) continue;
    det.pixels.push_back(*grid[id]);
    const Vec2d xy = spec.CornerXY(id);
    det.board_points.emplace_back(xy.x(), xy.y(), 0.0);
    det.indices.emplace_back(id % spec.Cols(), id / spec.Cols());
    det.from_edges += by_edges[id];
  }
  const int n = static_cast<int>(det.pixels.size());
  det.complete = n == total;
  det.found = n >= o.min_corners && (o.allow_partial || det.complete);
  det.status = std::string(det.found ? "" : "too few corners: ") + "charuco " + std::to_string(n) + " of " +
               std::to_string(total) + " corners from " + std::to_string(f.markers) + " markers" +
               (use_flipped ? " (mirrored)" : "");
  if (!det.found) det.pixels.clear(), det.board_points.clear(), det.indices.clear();
  return det;
}

}  // namespace hovs::calib
