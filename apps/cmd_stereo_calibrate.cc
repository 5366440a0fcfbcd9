// hovs stereo-calibrate: the relative pose of two units from ArUco board pairs (a stereo_aruco dataset, synthetic
// or real). Models: the manifest's units (exact rigs), or --left-model / --right-model (calibrated polynomial
// models). Writes stereo.json (relative pose, baseline, standard deviations, per-pair errors, detection counts,
// and with a synthetic manifest the errors against the true rig), stereo.yaml (OpenCV FileStorage: R, T) and
// summary.txt; the folder is replaced atomically.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <algorithm>
#include <set>
#include <tuple>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "depth/stereo.h"
#include "depth/stereo_calibration.h"
#include "raytrace/render.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

scenes::BoardSpec BoardFromJson(const nlohmann::json& b, const std::string& where) {
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

}  // namespace

Runner SetupStereoCalibrate(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string dataset, out = "results/stereo-calibration", left_model, right_model, model_kind = "auto";
    double huber = 1.0, marker_check_px = 2.0;
    std::string corner_refinement = "edges";
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--dataset", o->dataset, "stereo_aruco dataset manifest (two units per frame)")->required();
  sub->add_option("--left-model", o->left_model, "calibrated model of the first unit (calib_results.txt or calibration.json)");
  sub->add_option("--model-kind", o->model_kind, "with calibration.json models: auto (physical if present) | physical | polynomial | unified")
      ->capture_default_str();
  sub->add_option("--right-model", o->right_model, "calibrated model of the second unit");
  sub->add_option("--huber", o->huber, "robust loss scale, px")->check(Bounded(0, 1000, true))->capture_default_str();
  sub->add_option("--marker-check", o->marker_check_px,
                  "drop markers with a corner this far (px) from the board pose of the other corners; 0: keep all")->check(Bounded(0, 1000))
      ->capture_default_str();
  sub->add_option("--corner-refinement", o->corner_refinement,
                  "marker corners: edges (where the marker's two sides, measured along their length, meet) | "
                  "subpix (cornerSubPix only)")
      ->check(CLI::IsMember({"edges", "subpix"}))
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    // Options first: a bad one is reported before minutes of detection.
    HOVS_REQUIRE(std::isfinite(o->huber) && o->huber > 0, "--huber", "must be a positive scale in px (got ", o->huber, ")");
    HOVS_REQUIRE(std::isfinite(o->marker_check_px) && o->marker_check_px >= 0, "--marker-check",
                 "must be a distance >= 0 px, 0 keeping every marker (got ", o->marker_check_px, ")");
    const fs::path manifest(o->dataset);
    const auto m = LoadDatasetManifest(manifest);
    const auto& units = m.at("units");
    HOVS_REQUIRE(units.size() >= 2, o->dataset, "stereo calibration needs two units; the manifest has ", units.size());
    const auto ul = scenes::UnitFromJson(units[0], o->dataset + " (units)");
    const auto ur = scenes::UnitFromJson(units[1], o->dataset + " (units)");
    HOVS_REQUIRE(m.contains("boards") && !m["boards"].empty(), o->dataset,
                 "the manifest does not describe the board (key 'boards')");
    const scenes::BoardSpec spec = BoardFromJson(m["boards"][0], o->dataset + " (boards[0])");
    std::map<int, Vec3d> board;
    for (const auto& [id, p] : spec.Corners()) board[id] = Vec3d(p.x(), p.y(), 0);
    const AnyModel left = o->left_model.empty() ? AnyModel::Exact(ul.rig) : LoadCalibratedModel(o->left_model, o->model_kind);
    const AnyModel right = o->right_model.empty() ? AnyModel::Exact(ur.rig) : LoadCalibratedModel(o->right_model, o->model_kind);
    depth::MarkerDetectOptions dop;
    dop.dictionary = spec.dictionary;
    dop.corner_refinement = o->corner_refinement;
    const depth::MarkerDetector dl(left, dop), dr(right, dop);

    std::vector<depth::StereoPairObservation> pairs;
    nlohmann::json detections = nlohmann::json::array();
    for (const auto& fr : m.at("frames")) {
      depth::StereoPairObservation p;
      p.name = "frame" + std::to_string(fr.at("id").get<int>());
      bool have_l = false, have_r = false;
      for (const auto& v : fr.at("views")) {
        const fs::path img = manifest.parent_path() / v.at("image").get<std::string>();
        if (v.at("unit") == ul.name) p.left = dl.Detect(LoadImage8(img)), have_l = true;
        if (v.at("unit") == ur.name) p.right = dr.Detect(LoadImage8(img)), have_r = true;
      }
      HOVS_REQUIRE(have_l && have_r, o->dataset, p.name, " lacks an image of both units");
      // Markers whose corners disagree with the unit's board pose (partly hidden, still decoded) are dropped.
      std::vector<int> bad_l, bad_r;
      if (o->marker_check_px > 0) {
        bad_l = depth::RejectInconsistentMarkers(left, &p.left, board, o->marker_check_px);
        bad_r = depth::RejectInconsistentMarkers(right, &p.right, board, o->marker_check_px);
      }
      const auto by_edges = [](const std::vector<depth::CornerObservation>& cs) {
        return std::count_if(cs.begin(), cs.end(), [](const auto& c) { return c.from_edges; });
      };
      detections.push_back({{"pair", p.name}, {"left_corners", p.left.size()}, {"right_corners", p.right.size()},
                            {"left_from_edges", by_edges(p.left)}, {"right_from_edges", by_edges(p.right)},
                            {"inconsistent_markers_left", bad_l}, {"inconsistent_markers_right", bad_r}});
      if (!global->quiet)
        std::fprintf(stderr, "  %s: %zu corners left, %zu right\n", p.name.c_str(), p.left.size(), p.right.size());
      pairs.push_back(std::move(p));
    }
    depth::StereoCalibrationOptions so;
    so.huber_px = o->huber;
    const depth::StereoCalibration c = OnInput(o->dataset, [&] { return depth::CalibrateStereo(left, right, pairs, board, so); });
    // The article's method on the same detections, for comparison: each unit's board pose on its own, then the
    // relative pose from the 3-D residual alone.
    std::optional<depth::StereoCalibration> c3;
    std::string c3_error;
    try {
      depth::StereoCalibrationOptions s3 = so;
      s3.residual = "3d";
      c3 = OnInput(o->dataset, [&] { return depth::CalibrateStereo(left, right, pairs, board, s3); });
    } catch (const Error& e) {
      c3_error = e.what();
    }

    const auto& q = c.right_from_left.rotation;
    const Vec3d& t = c.right_from_left.translation;
    nlohmann::json per = nlohmann::json::array();
    for (size_t k = 0; k < c.pair_names.size(); ++k)
      per.push_back({{"pair", c.pair_names[k]}, {"rms_left_px", c.pair_rms_left_px[k]},
                     {"rms_right_px", c.pair_rms_right_px[k]}, {"corners_left", c.pair_corners_left[k]},
                     {"corners_right", c.pair_corners_right[k]},
                     {"above_10px", std::max(c.pair_rms_left_px[k], c.pair_rms_right_px[k]) > 10}});
    nlohmann::json j = {{"tool", "hovs stereo-calibrate"}, {"versions", Versions()},
                        {"dataset", o->dataset}, {"models", {left.KindName(), right.KindName()}},
                        {"right_from_left", {{"q", {q.w(), q.x(), q.y(), q.z()}}, {"t", {t.x(), t.y(), t.z()}}}},
                        {"baseline_m", c.baseline}, {"sigma_baseline_m", c.sigma_baseline},
                        {"sigma_translation_m", {c.sigma_translation.x(), c.sigma_translation.y(), c.sigma_translation.z()}},
                        {"sigma_rotation_deg", {c.sigma_rotation_deg.x(), c.sigma_rotation_deg.y(), c.sigma_rotation_deg.z()}},
                        {"rms_px", c.rms_px}, {"converged", c.converged}, {"solver", c.solver_report},
                        {"pairs", per}, {"detections", detections}};
    nlohmann::json outl = nlohmann::json::array();
    for (const auto& x : c.outliers)
      outl.push_back({{"pair", x.pair}, {"unit", x.unit}, {"corner", x.corner}, {"residual_px", x.residual_px}});
    j["outliers"] = {{"threshold_px", so.outlier_px}, {"dropped", outl}};
    j["corner_refinement"] = o->corner_refinement;
    if (c3) {
      const auto& q3 = c3->right_from_left.rotation;
      const Vec3d& t3 = c3->right_from_left.translation;
      j["article_3d_residual"] = {{"method", "per-unit board poses, then right_from_left from T P_left - P_right (the article's 3.2.2)"},
                                  {"right_from_left", {{"q", {q3.w(), q3.x(), q3.y(), q3.z()}}, {"t", {t3.x(), t3.y(), t3.z()}}}},
                                  {"baseline_m", c3->baseline}, {"rms_3d_mm", 1e3 * c3->rms_3d_m},
                                  {"rms_px", c3->rms_px}, {"converged", c3->converged}};
    } else {
      j["article_3d_residual"] = {{"error", c3_error}};
    }
    std::string summary = "hovs stereo-calibrate: " + std::to_string(c.pair_names.size()) + " pairs, baseline " +
                          std::to_string(c.baseline) + " m (sigma " + std::to_string(c.sigma_baseline * 1e3) +
                          " mm), RMS " + std::to_string(c.rms_px) + " px, " + std::to_string(c.outliers.size()) +
                          " outlier corners dropped (listed in stereo.json)\n";
    {
      // Against the true rig (synthetic manifests). With calibrated models the relative pose is that of the models'
      // frames, which for these units coincide with the mirror frames up to the calibration's error.
      const Rigid3d truth = ur.world_from_mirror.Inverse() * ul.world_from_mirror;
      const double rot = 2 * std::asin(std::min(1.0, (c.right_from_left.rotation * truth.rotation.conjugate()).vec().norm())) * 180 / M_PI;
      j["ground_truth"] = {{"baseline_m", truth.translation.norm()},
                           {"baseline_error_mm", 1e3 * (c.baseline - truth.translation.norm())},
                           {"translation_error_mm", 1e3 * (c.right_from_left.translation - truth.translation).norm()},
                           {"rotation_error_deg", rot}};
      char line[200];
      std::snprintf(line, sizeof line, "  against the true rig: baseline error %.3f mm, rotation error %.4f deg\n",
                    1e3 * (c.baseline - truth.translation.norm()), rot);
      summary += line;
      if (c3) {
        const double rot3 =
            2 * std::asin(std::min(1.0, (c3->right_from_left.rotation * truth.rotation.conjugate()).vec().norm())) * 180 / M_PI;
        j["article_3d_residual"]["ground_truth"] = {{"baseline_error_mm", 1e3 * (c3->baseline - truth.translation.norm())},
                                                    {"translation_error_mm", 1e3 * (c3->right_from_left.translation - truth.translation).norm()},
                                                    {"rotation_error_deg", rot3}};
        std::snprintf(line, sizeof line,
                      "  the article's 3-D residual method on the same corners: baseline error %.3f mm, rotation error "
                      "%.4f deg, reprojection RMS %.3f px\n", 1e3 * (c3->baseline - truth.translation.norm()), rot3, c3->rms_px);
        summary += line;
      }
      // Sparse depth: every marker corner seen by both units, triangulated with the calibrated pose and models,
      // against its true range from the left viewpoint (the board's true pose in the manifest).
      const depth::StereoRig rig{left, right, c.right_from_left};
      struct Band { double lo, hi; std::vector<double> rel; };
      std::vector<Band> bands = {{0, 1, {}}, {1, 2, {}}, {2, 3, {}}, {3, 5, {}}, {5, 1e9, {}}};
      double worst = 0, ss = 0;
      int n = 0, excluded = 0;
      std::vector<double> all_rel;
      // The worst corners, for diagnosis: where they are (range, angle to the baseline), the predicted range
      // sigma for 0.1 px of corner noise, and the rays' gap.
      // Also each unit's corner error against the board's true pose projected through the unit's model (the
      // exact ground truth with the exact models).
      struct Worst { double rel, range, theta_deg, sigma_rel, gap_mm; std::string pair; int corner; double err_l, err_r; bool edges_l, edges_r; };
      std::vector<Worst> worst_list;
      const double px_rad = 0.1 * (M_PI / 2) / std::max(1, ul.rig.camera.width / 2);   // ~0.1 px at the rim
      const Vec3d base_dir = c.right_from_left.Inverse().translation.normalized();
      std::set<std::tuple<std::string, std::string, int>> outlier_set;
      for (const auto& x : c.outliers) outlier_set.insert({x.pair, x.unit, x.corner});
      for (const auto& fr : m.at("frames")) {
        if (!fr.contains("world_from_board")) continue;
        const std::string name = "frame" + std::to_string(fr.at("id").get<int>());
        const auto it = std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return p.name == name; });
        if (it == pairs.end()) continue;
        const auto& wb = fr["world_from_board"];
        const Rigid3d world_from_board(Eigen::Quaterniond(wb["q"][0], wb["q"][1], wb["q"][2], wb["q"][3]),
                                       Vec3d(wb["t"][0], wb["t"][1], wb["t"][2]));
        const Rigid3d left_from_board = ul.world_from_mirror.Inverse() * world_from_board;
        const Rigid3d right_from_board = ur.world_from_mirror.Inverse() * world_from_board;
        std::map<int, Vec2d> rpx;
        std::map<int, bool> redges;
        for (const auto& p : it->right) rpx[p.id] = p.pixel, redges[p.id] = p.from_edges;
        for (const auto& p : it->left) {
          const auto r = rpx.find(p.id);
          const auto b = board.find(p.id);
          if (r == rpx.end() || b == board.end()) continue;
          // Corners the calibration rejected as mis-detected (listed in stereo.json) are not triangulated.
          if (outlier_set.count({name, "left", p.id}) || outlier_set.count({name, "right", p.id})) {
            ++excluded;
            continue;
          }
          Vec3d ol, bl, orr, br;
          if (!left.RayFromImg(p.pixel, &ol, &bl) || !right.RayFromImg(r->second, &orr, &br)) continue;
          const auto tri = depth::Triangulate(rig, ol, bl, orr, br, px_rad);
          if (!tri.ok) continue;
          const Vec3d X = left_from_board * b->second;
          const double true_range = X.norm();
          const double rel = (tri.range_left - true_range) / true_range;
          Vec2d tl, tr;
          const double el = left.ImgFromPointUnbounded(X, &tl) ? (tl - p.pixel).norm() : -1;
          const double er = right.ImgFromPointUnbounded(right_from_board * b->second, &tr) ? (tr - r->second).norm() : -1;
          worst_list.push_back({std::abs(rel), true_range,
                                std::acos(std::clamp(X.normalized().dot(base_dir), -1.0, 1.0)) * 180 / M_PI,
                                tri.sigma_range / true_range, 1e3 * tri.gap, name, p.id, el, er, p.from_edges, redges[p.id]});
          for (auto& band : bands)
            if (true_range >= band.lo && true_range < band.hi) band.rel.push_back(std::abs(rel));
          worst = std::max(worst, std::abs(rel)), ss += rel * rel, ++n;
          all_rel.push_back(std::abs(rel));
        }
      }
      nlohmann::json tab = nlohmann::json::array();
      for (auto& band : bands) {
        if (band.rel.empty()) continue;
        std::sort(band.rel.begin(), band.rel.end());
        tab.push_back({{"range_m", {band.lo, band.hi > 1e8 ? -1 : band.hi}}, {"points", band.rel.size()},
                       {"median_rel_error", band.rel[band.rel.size() / 2]}, {"max_rel_error", band.rel.back()}});
      }
      if (n > 0) {
        std::sort(all_rel.begin(), all_rel.end());
        j["sparse_depth"] = {{"points", n}, {"rms_rel_error", std::sqrt(ss / n)}, {"max_rel_error", worst},
                             {"median_rel_error", all_rel[all_rel.size() / 2]},
                             {"p95_rel_error", all_rel[std::min(all_rel.size() - 1, all_rel.size() * 95 / 100)]},
                             {"excluded_outlier_corners", excluded}, {"bands", tab}};
        std::sort(worst_list.begin(), worst_list.end(), [](const Worst& a, const Worst& b) { return a.rel > b.rel; });
        const auto listing = [](const std::vector<const Worst*>& ws) {
          nlohmann::json wl = nlohmann::json::array();
          for (size_t k = 0; k < std::min<size_t>(10, ws.size()); ++k) {
            const Worst& w = *ws[k];
            wl.push_back({{"pair", w.pair}, {"corner", w.corner}, {"rel_error", w.rel}, {"range_m", w.range},
                          {"angle_to_baseline_deg", w.theta_deg}, {"predicted_sigma_rel_0.1px", w.sigma_rel},
                          {"ray_gap_mm", w.gap_mm}, {"left_corner_error_px", w.err_l},
                          {"right_corner_error_px", w.err_r},
                          {"left_refinement", w.edges_l ? "edges" : "window"},
                          {"right_refinement", w.edges_r ? "edges" : "window"}});
          }
          return wl;
        };
        std::vector<const Worst*> all_worst, cond_worst;
        // Away from the baseline direction (where a pixel of disparity is a large fraction of the range and the
        // dense depth masks too): the figures the geometry allows.
        constexpr double kMinAngle = 15;
        std::vector<double> cond;
        for (const auto& w : worst_list) {
          all_worst.push_back(&w);
          if (w.theta_deg >= kMinAngle && w.theta_deg <= 180 - kMinAngle) cond.push_back(w.rel), cond_worst.push_back(&w);
        }
        j["sparse_depth"]["worst_points"] = listing(all_worst);
        if (!cond.empty()) {
          std::sort(cond.begin(), cond.end());
          j["sparse_depth"]["conditioned"] = {
              {"min_angle_to_baseline_deg", kMinAngle}, {"points", cond.size()},
              {"median_rel_error", cond[cond.size() / 2]},
              {"p95_rel_error", cond[std::min(cond.size() - 1, cond.size() * 95 / 100)]}, {"max_rel_error", cond.back()},
              {"worst_points", listing(cond_worst)}};
          std::snprintf(line, sizeof line, "  of them %zu at least %.0f deg from the baseline: worst %.3f %%\n",
                        cond.size(), kMinAngle, 100 * cond.back());
          summary += line;
        }
        std::snprintf(line, sizeof line, "  sparse depth of %d marker corners: RMS %.3f %%, worst %.3f %%\n", n,
                      100 * std::sqrt(ss / n), 100 * worst);
        summary += line;
      }
    }
    StagedDirectory staged(o->out, "stereo-calibrate");
    // Reprojection figure per pair and unit (the article's Fig. 28): a crop of the catadioptric image around
    // the board, detected corners (green circles), reprojected corners (red crosses) and the residual magnified
    // 20 times (yellow).
    fs::create_directories(staged.staging() / "figures");
    std::map<std::string, std::pair<fs::path, fs::path>> images;
    for (const auto& fr : m.at("frames")) {
      auto& e = images["frame" + std::to_string(fr.at("id").get<int>())];
      for (const auto& v : fr.at("views")) {
        const fs::path img = manifest.parent_path() / v.at("image").get<std::string>();
        if (v.at("unit") == ul.name) e.first = img;
        if (v.at("unit") == ur.name) e.second = img;
      }
    }
    for (size_t k = 0; k < c.pair_names.size(); ++k) {
      const auto& name = c.pair_names[k];
      const auto& obs = *std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return p.name == name; });
      for (int side = 0; side < 2; ++side) {
        const auto& corners = side == 0 ? obs.left : obs.right;
        if (corners.empty()) continue;
        const AnyModel& model = side == 0 ? left : right;
        const Rigid3d mirror_from_board = side == 0 ? c.left_from_board[k] : c.right_from_left * c.left_from_board[k];
        const unwrap::Image8 im = LoadImage8(side == 0 ? images[name].first : images[name].second);
        double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
        for (const auto& p : corners)
          x0 = std::min(x0, p.pixel.x()), x1 = std::max(x1, p.pixel.x()), y0 = std::min(y0, p.pixel.y()),
          y1 = std::max(y1, p.pixel.y());
        const cv::Rect roi = cv::Rect(cv::Point(int(x0) - 40, int(y0) - 40), cv::Point(int(x1) + 40, int(y1) + 40)) &
                             cv::Rect(0, 0, im.width, im.height);
        cv::Mat full(im.height, im.width, im.channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<uint8_t*>(im.data.data()));
        cv::Mat crop;
        if (im.channels == 3) cv::cvtColor(full(roi), crop, cv::COLOR_RGB2BGR); else cv::cvtColor(full(roi), crop, cv::COLOR_GRAY2BGR);
        const double scale = 800.0 / std::max(roi.width, roi.height);
        cv::resize(crop, crop, cv::Size(), scale, scale, cv::INTER_CUBIC);
        const auto at = [&](const Vec2d& p) {
          return cv::Point2d((p.x() - roi.x + 0.5) * scale - 0.5, (p.y() - roi.y + 0.5) * scale - 0.5);
        };
        for (const auto& p : corners) {
          const auto it = board.find(p.id);
          Vec2d uv;
          if (it == board.end() || !model.ImgFromMirror(mirror_from_board * it->second, &uv)) continue;
          cv::circle(crop, at(p.pixel), 5, cv::Scalar(0, 200, 0), 1, cv::LINE_AA);
          cv::drawMarker(crop, at(uv), cv::Scalar(0, 0, 255), cv::MARKER_CROSS, 8, 1, cv::LINE_AA);
          cv::line(crop, at(p.pixel), at(p.pixel + 20 * (uv - p.pixel)), cv::Scalar(0, 220, 255), 1, cv::LINE_AA);
        }
        char text[160];
        std::snprintf(text, sizeof text, "%s %s: RMS %.3f px, %zu corners (residuals x20)", name.c_str(),
                      side == 0 ? ul.name.c_str() : ur.name.c_str(),
                      side == 0 ? c.pair_rms_left_px[k] : c.pair_rms_right_px[k], corners.size());
        cv::putText(crop, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
        cv::putText(crop, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        const fs::path fig = staged.staging() / "figures" / (name + "_" + (side == 0 ? ul.name : ur.name) + ".png");
        HOVS_REQUIRE(cv::imwrite(fig.string(), crop), fig.string(), "cannot write the figure");
      }
    }
    WriteFileAtomic(staged.staging() / "stereo.json", j.dump(1));
    {
      // OpenCV FileStorage (stereoCalibrate's names: R, T).
      cv::FileStorage fs((staged.staging() / "stereo.yaml").string(), cv::FileStorage::WRITE);
      HOVS_REQUIRE(fs.isOpened(), (staged.staging() / "stereo.yaml").string(), "cannot write");
      const Mat3<double> R = q.toRotationMatrix();
      cv::Mat Rm(3, 3, CV_64F), Tm(3, 1, CV_64F);
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) Rm.at<double>(r, k) = R(r, k);
        Tm.at<double>(r) = t(r);
      }
      fs << "R" << Rm << "T" << Tm << "baseline" << c.baseline << "sigma_baseline" << c.sigma_baseline
         << "rms_px" << c.rms_px << "frames" << "right mirror frame from left mirror frame, metres";
    }
    WriteFileAtomic(staged.staging() / "summary.txt", summary);
    staged.Commit();
    if (!global->quiet) std::printf("%s", summary.c_str());
    return 0;
  };
}

}  // namespace hovs::apps
