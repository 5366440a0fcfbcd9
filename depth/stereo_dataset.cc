#include "depth/stereo_dataset.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/json.h"
#include "core/manifest.h"
#include "io/image_io.h"
#include "scenes/ground_truth.h"

namespace hovs::depth {
namespace {

scenes::BoardSpec ArucoBoardFromJson(const nlohmann::json& b, const std::string& where) {
  scenes::BoardSpec s;
  HOVS_REQUIRE(JsonText(b, "type") == "aruco", where, "the board is not an ArUco board");
  s.kind = scenes::BoardSpec::Kind::kAruco;
  const std::vector<double> markers = JsonNumbers(b, "markers", 2, 2, where);
  HOVS_REQUIRE(markers[0] == std::floor(markers[0]) && markers[1] == std::floor(markers[1]) && markers[0] >= 1 &&
                   markers[1] >= 1 && markers[0] <= 1000 && markers[1] <= 1000,
               where + ".markers", "expected two whole numbers in 1..1000");
  s.markers_x = static_cast<int>(markers[0]), s.markers_y = static_cast<int>(markers[1]);
  s.marker_length = JsonNumber(b, "marker_length", where), s.marker_separation = JsonNumber(b, "separation", where);
  s.margin = JsonNumber(b, "margin", where);
  HOVS_REQUIRE(b.contains("dictionary") && b["dictionary"].is_string(), where, "needs the string 'dictionary'");
  s.dictionary = b["dictionary"].get<std::string>();
  scenes::CheckBoard(s, where);
  return s;
}

int FromEdges(const std::vector<CornerObservation>& cs) {
  return static_cast<int>(std::count_if(cs.begin(), cs.end(), [](const auto& c) { return c.from_edges; }));
}

}  // namespace

Rigid3d StereoDataset::TrueRightFromLeft() const {
  return right_unit.world_from_mirror.Inverse() * left_unit.world_from_mirror;
}

StereoDataset LoadStereoDataset(const std::filesystem::path& manifest) {
  const std::string where = manifest.string();
  const auto m = LoadDatasetManifest(manifest);
  const auto& units = m.at("units");
  HOVS_REQUIRE(units.size() >= 2, where, "stereo calibration needs two units; the manifest has ", units.size());
  StereoDataset d;
  d.manifest = manifest;
  d.left_unit = scenes::UnitFromJson(units[0], where + " (units)");
  d.right_unit = scenes::UnitFromJson(units[1], where + " (units)");
  HOVS_REQUIRE(m.contains("boards") && !m["boards"].empty(), where,
               "the manifest does not describe the board (key 'boards')");
  d.board_spec = ArucoBoardFromJson(m["boards"][0], where + " (boards[0])");
  for (const auto& [id, p] : d.board_spec.Corners()) d.board[id] = Vec3d(p.x(), p.y(), 0);
  for (const auto& fr : m.at("frames")) {
    StereoFrame f;
    f.name = "frame" + std::to_string(fr.at("id").get<int>());
    for (const auto& v : fr.at("views")) {
      const std::filesystem::path img = manifest.parent_path() / v.at("image").get<std::string>();
      if (v.at("unit") == d.left_unit.name) f.left_image = img;
      if (v.at("unit") == d.right_unit.name) f.right_image = img;
    }
    HOVS_REQUIRE(!f.left_image.empty() && !f.right_image.empty(), where, f.name, " lacks an image of both units");
    if (fr.contains("world_from_board")) {
      const auto& wb = fr["world_from_board"];
      f.world_from_board = Rigid3d(Eigen::Quaterniond(wb["q"][0], wb["q"][1], wb["q"][2], wb["q"][3]),
                                   Vec3d(wb["t"][0], wb["t"][1], wb["t"][2]));
    }
    d.frames.push_back(f);
  }
  return d;
}

std::vector<StereoPairObservation> DetectStereoPairs(const StereoDataset& d, const AnyModel& left,
                                                     const AnyModel& right, const StereoDetectOptions& options,
                                                     std::vector<PairDetection>* detections,
                                                     const std::function<void(const PairDetection&)>& progress) {
  MarkerDetectOptions mo = options.markers;
  mo.dictionary = d.board_spec.dictionary;
  const MarkerDetector dl(left, mo), dr(right, mo);
  std::vector<StereoPairObservation> pairs;
  for (const StereoFrame& f : d.frames) {
    StereoPairObservation p;
    p.name = f.name;
    p.left = dl.Detect(unwrap::LoadImage8(f.left_image));
    p.right = dr.Detect(unwrap::LoadImage8(f.right_image));
    // Markers whose corners disagree with the unit's board pose (partly hidden, still decoded) are dropped.
    PairDetection rec;
    rec.pair = p.name;
    if (options.marker_check_px > 0) {
      rec.inconsistent_left = RejectInconsistentMarkers(left, &p.left, d.board, options.marker_check_px);
      rec.inconsistent_right = RejectInconsistentMarkers(right, &p.right, d.board, options.marker_check_px);
    }
    rec.left_corners = static_cast<int>(p.left.size()), rec.right_corners = static_cast<int>(p.right.size());
    rec.left_from_edges = FromEdges(p.left), rec.right_from_edges = FromEdges(p.right);
    if (detections) detections->push_back(rec);
    if (progress) progress(rec);
    pairs.push_back(std::move(p));
  }
  return pairs;
}

}  // namespace hovs::depth
