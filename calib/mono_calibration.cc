#include "calib/mono_calibration.h"

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "calib/rim_positioning.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "io/image_io.h"

namespace hovs::calib {
namespace {

nlohmann::json DetectionJson(const ImageDetection& d) {
  nlohmann::json row = {{"image", d.image},
                        {"status", d.status},
                        {"found", d.found},
                        {"complete", d.complete},
                        {"corners", d.corners},
                        {"from_edges", d.from_edges},
                        {"candidates", d.candidates},
                        {"corner_refinement", d.corner_refinement},
                        {"rejected", d.rejected},
                        {"rejected_reason", d.rejected_reason},
                        {"worst_label_error", d.worst_label_error}};
  if (d.to_truth) row["rms_to_truth_px"] = d.to_truth->rms_px, row["max_to_truth_px"] = d.to_truth->max_px;
  return row;
}

// The board's flex (calib/board_warp.h) in mm: each axis' bulge and their sum at the centre; null when not
// estimated.
nlohmann::json BoardFlexJson(bool estimated, const std::array<double, 2>& warp,
                             const std::vector<std::array<double, 2>>& per_image) {
  if (!estimated) return nullptr;
  nlohmann::json j = {{"x_mm", 1e3 * warp[0]}, {"y_mm", 1e3 * warp[1]}, {"centre_mm", 1e3 * (warp[0] + warp[1])}};
  if (!per_image.empty()) {
    j["per_image_mm"] = nlohmann::json::array();
    for (const auto& w : per_image) j["per_image_mm"].push_back({1e3 * w[0], 1e3 * w[1]});
    j["note"] = "one warp per image; x_mm, y_mm: their mean";
  }
  return j;
}

// A board pose as {"q": [w, x, y, z], "t": [x, y, z]} (the form of every hovs pose), model frame from board frame.
nlohmann::json PoseJson(const Rigid3d& p) {
  const auto& q = p.rotation;
  return {{"q", {q.w(), q.x(), q.y(), q.z()}}, {"t", {p.translation.x(), p.translation.y(), p.translation.z()}}};
}

// Every image's board pose, so that users reproject without solving them again.
nlohmann::json BoardPosesJson(const std::vector<Rigid3d>& cam_from_board, const std::vector<BoardObservation>& obs) {
  nlohmann::json poses = nlohmann::json::array();
  for (size_t i = 0; i < cam_from_board.size() && i < obs.size(); ++i) {
    nlohmann::json pj = PoseJson(cam_from_board[i]);
    pj["image"] = obs[i].image;
    poses.push_back(pj);
  }
  return poses;
}

nlohmann::json PolynomialJson(const PolynomialCalibration& r, const std::vector<BoardObservation>& obs) {
  const auto& m = r.model;
  nlohmann::json j = {{"model", "polynomial"},
                      {"cx", m.cx},
                      {"cy", m.cy},
                      {"c", m.c},
                      {"d", m.d},
                      {"e", m.e},
                      {"poly", m.poly},
                      {"inv_poly", m.inv_poly},
                      {"inv_poly_max_error_px", m.inv_poly_error_px},
                      {"inverse",
                       {{"chebyshev", m.inv_cheb},
                        {"theta_range", {m.inv_theta_lo, m.inv_theta_hi}},
                        {"max_error_px", m.inv_error_px}}},
                      {"rho_range", {m.rho_min, m.rho_max}},
                      {"width", m.width},
                      {"height", m.height},
                      {"rms_px", r.rms},
                      {"mean_px", r.mean},
                      {"initial_rms_px", r.initial_rms},
                      {"board_flex", BoardFlexJson(r.board_flex, r.board_warp, r.image_warps)},
                      {"converged", r.converged},
                      {"solver", r.solver_report},
                      {"stddev", r.stddev}};
  nlohmann::json per = nlohmann::json::array();
  for (size_t i = 0; i < obs.size(); ++i)
    per.push_back({{"image", obs[i].image},
                   {"corners", obs[i].pixels.size()},
                   {"rms_px", r.per_image_rms[i]},
                   {"mean_px", r.per_image_mean[i]},
                   {"above_5px", r.per_image_mean[i] > 5.0}});
  if (m.HasDecentering()) j["decentering"] = {m.p1, m.p2};  // hovs' extension (core/polynomial.h)
  j["per_image"] = per;
  j["board_poses"] = BoardPosesJson(r.cam_from_board, obs);
  j["board_poses_frame"] = "mirror_from_board: hovs' mirror frame from the board's (x, y on the board, metres)";
  nlohmann::json outl = nlohmann::json::array();
  for (const auto& o : r.outliers)
    outl.push_back({{"image", o.image},
                    {"corner", o.corner},
                    {"residual_px", o.residual_px},
                    {"residual_after_px", o.residual_after_px}});
  j["outliers"] = outl;
  j["outlier_threshold_px"] = r.outlier_threshold_px;
  return j;
}

// The detector's totals over the images, and the corners' RMS distance to the exact ones (weighted by corners).
struct DetectionTotals {
  int complete = 0, corners = 0, from_edges = 0, with_truth = 0;
  double rms_to_truth_px = 0;
};

DetectionTotals Totals(const std::vector<ImageDetection>& detection) {
  DetectionTotals t;
  double ss = 0;
  for (const auto& d : detection) {
    t.complete += d.complete;
    if (!d.found) continue;
    t.corners += d.corners, t.from_edges += d.from_edges;
    if (d.to_truth) ss += std::pow(d.to_truth->rms_px, 2) * d.corners, t.with_truth += d.corners;
  }
  if (t.with_truth) t.rms_to_truth_px = std::sqrt(ss / t.with_truth);
  return t;
}

std::vector<Vec2d> PhysicalRimPoints(const CalibrationInput& input, const CatadioptricCamera<double>& nominal,
                                     const std::function<void(const std::string&)>& warn) {
  std::vector<Vec2d> points;
  for (const auto& path : input.paths) {
    const cv::Mat g = ReadGreyImage(path);
    RimEdge edge;
    try {
      LocateMirror(g.data, g.cols, g.rows, nominal, {}, &edge, path.string());
    } catch (const Error& e) {
      if (warn) warn(std::string(e.what()) + " (the image is left out of the rim fit)");
      continue;
    }
    points.insert(points.end(), edge.points.begin(), edge.points.end());
  }
  HOVS_REQUIRE(points.size() >= 20, "--physical",
               "the rim of the mirror image was not found in the "
               "images (--no-rim calibrates without it)");
  return points;
}

}  // namespace

cv::Mat ReadGreyImage(const std::filesystem::path& path) {
  io::Image8Bits im = io::ReadImage8(path);
  cv::Mat m(im.height, im.width, im.channels == 3 ? CV_8UC3 : CV_8UC1, im.data.data());
  cv::Mat grey;
  if (im.channels == 3)
    cv::cvtColor(m, grey, cv::COLOR_RGB2GRAY);
  else
    grey = m.clone();
  return grey;
}

void DetectInto(const std::filesystem::path& path, const std::string& name, const CheckerboardDetectOptions& o,
                const std::vector<Vec2d>* truth, CalibrationInput* in) {
  const cv::Mat grey = ReadGreyImage(path);
  if (in->width == 0) in->width = grey.cols, in->height = grey.rows;
  HOVS_REQUIRE(grey.cols == in->width && grey.rows == in->height, path.string(), "image size ", grey.cols, "x",
               grey.rows, " differs from the first image's ", in->width, "x", in->height);
  const auto det = o.charuco ? DetectCharuco(grey, o) : DetectCheckerboard(grey, o);
  ImageDetection d;
  d.image = name, d.status = det.status, d.corner_refinement = o.corner_refinement;
  d.found = det.found, d.complete = det.complete;
  d.corners = static_cast<int>(det.pixels.size()), d.from_edges = det.from_edges, d.candidates = det.candidates;
  d.rejected = det.rejected, d.rejected_reason = det.rejected_reason, d.worst_label_error = det.worst_label_error;
  if (truth && det.found) d.to_truth = CompareWithTruth(det.pixels, *truth);
  in->detection.push_back(d);
  if (det.found) in->observations.push_back(ToObservation(det, name)), in->paths.push_back(path);
}

CalibrationInput CornerTableInput(const std::filesystem::path& table, int width, int height) {
  CalibrationInput in;
  in.observations = LoadCornerCsv(table);
  in.width = width, in.height = height;
  in.description = {{"corners", table.string()}, {"size", {width, height}}};
  for (const auto& ob : in.observations)
    for (const auto& p : ob.pixels)
      HOVS_REQUIRE(p.x() >= -0.5 && p.y() >= -0.5 && p.x() <= width - 0.5 && p.y() <= height - 0.5, table.string(),
                   "corner (", p.x(), ", ", p.y(), ") of ", ob.image, " lies outside the ", width, "x", height,
                   " image");
  return in;
}

CalibrationInput ImageFolderInput(const std::filesystem::path& folder, const CheckerboardDetectOptions& options) {
  CalibrationInput in;
  for (const auto& f : ListImageFiles(folder)) DetectInto(f, f.filename().string(), options, nullptr, &in);
  in.description = {{"images", folder.string()},
                    {"corners", "hovs checkerboard detector"},
                    {"board", {options.board.cols, options.board.rows, options.board.square}}};
  if (options.charuco)
    in.description["corners"] = "hovs ChArUco detector",
    in.description["board"] = {{"charuco", {options.charuco->squares_x, options.charuco->squares_y}},
                               {"square", options.charuco->square},
                               {"marker", options.charuco->marker},
                               {"dictionary", options.charuco->dictionary}};
  return in;
}

std::string CheckDetections(const CalibrationInput& input, const std::string& where) {
  std::string failed;
  for (const auto& d : input.detection)
    if (!d.found) failed += "; " + d.image + ": " + d.status;
  HOVS_REQUIRE(input.observations.size() >= 3, where, "only ", input.observations.size(), " of ",
               input.detection.size(), " images have a usable board (at least 3 needed)", failed);
  return failed.empty() ? failed : failed.substr(2);
}

CheckerboardSpec ParseBoardSpec(const std::string& text, const std::string& where) {
  CheckerboardSpec b;
  char x1 = 0, x2 = 0;
  int end = -1;  // where parsing stopped: nothing may follow (7x6x0.03x9 is not 7x6x0.03)
  HOVS_REQUIRE(std::sscanf(text.c_str(), "%d%c%d%c%lf%n", &b.cols, &x1, &b.rows, &x2, &b.square, &end) == 5 &&
                   x1 == 'x' && x2 == 'x' && end == static_cast<int>(text.size()),
               where, "expected COLSxROWSxSQUARE (inner corners, square in metres), e.g. 7x6x0.03 (got '", text, "')");
  b.Check(where);
  return b;
}

MonoCalibration CalibrateMono(const CalibrationInput& in, const MonoCalibrationOptions& options,
                              const std::function<void(const std::string&)>& warn) {
  MonoCalibration r;
  PolynomialCalibrationOptions po = options.polynomial;
  std::optional<PolynomialCalibration> chosen;
  for (int d : options.degrees) {
    po.degree = d;
    auto p = CalibratePolynomial(in.observations, in.width, in.height, po);
    r.orders.push_back({d, p.rms, p.mean, p.converged, p.per_image_mean});
    if (d == options.polynomial.degree) chosen = std::move(p);
  }
  r.polynomial = chosen ? *chosen : CalibratePolynomial(in.observations, in.width, in.height, options.polynomial);
  // The unified and physical models and OpenCV omnidir see the corners the polynomial solve kept.
  r.inliers = InlierObservations(in.observations, r.polynomial);
  r.unified = CalibrateUnified(r.inliers, in.width, in.height, r.polynomial, po.loss, po.loss_scale);
  if (options.physical_nominal) {
    const auto& nominal = *options.physical_nominal;
    HOVS_REQUIRE(nominal.camera.width == in.width && nominal.camera.height == in.height, "--physical",
                 "the nominal camera is ", nominal.camera.width, "x", nominal.camera.height, " but the images are ",
                 in.width, "x", in.height);
    PhysicalCalibrationOptions popt = options.physical;
    if (options.rim && !in.paths.empty()) popt.rim_points = PhysicalRimPoints(in, nominal, warn);
    r.physical = CalibratePhysical(r.inliers, nominal, r.polynomial, popt);
    r.rim_points = popt.rim_points.size();
  }
  if (options.omnidir) r.omnidir = RunOpenCvOmnidir(r.inliers, in.width, in.height);
  if (options.cross_validate > 0)
    r.cross_validation = CrossValidatePolynomial(r.inliers, in.width, in.height, options.polynomial,
                                                 options.cross_validate, r.polynomial.model);
  // The uncertainty is mapped (and the suggestions scored) over the polynomial model's calibrated annulus.
  UncertaintyOptions uo;
  uo.range_m = options.uncertainty_range_m;
  uo.centre = Vec2d(r.polynomial.model.cx, r.polynomial.model.cy);
  uo.rho_min = r.polynomial.model.rho_min, uo.rho_max = r.polynomial.model.rho_max;
  if (options.uncertainty) {
    if (r.polynomial.covariance.valid())
      r.polynomial_uncertainty =
          ProjectionUncertaintyMap(ParametricModel(r.polynomial.model), r.polynomial.covariance, uo);
    if (r.unified.covariance.valid())
      r.unified_uncertainty = ProjectionUncertaintyMap(ParametricModel(r.unified.model), r.unified.covariance, uo);
  }
  if (options.suggest > 0) {
    HOVS_REQUIRE(r.polynomial.covariance.valid(), "--suggest",
                 "the polynomial solve's covariance is not computable: no uncertainty to lower");
    // The board as the images show it: the image with the most corners.
    const auto largest =
        std::max_element(in.observations.begin(), in.observations.end(),
                         [](const auto& a, const auto& b) { return a.board_points.size() < b.board_points.size(); });
    SuggestOptions so;
    so.count = options.suggest;
    r.suggestions =
        SuggestBoardPoses(ParametricModel(r.polynomial.model), r.polynomial.covariance, largest->board_points, uo, so);
  }
  if (in.truth) {
    r.polynomial_vs_truth = CompareWithTruth(*in.truth, r.polynomial.model);
    if (r.physical) r.physical_vs_truth = CompareWithTruth(*in.truth, r.physical->rig);
  }
  return r;
}

nlohmann::json MonoCalibrationJson(const CalibrationInput& in, const MonoCalibrationOptions& options,
                                   const MonoCalibration& r) {
  nlohmann::json j;
  j["input"] = in.description;
  j["input"]["images"] = in.observations.size();
  if (!in.detection.empty()) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& d : in.detection) rows.push_back(DetectionJson(d));
    j["detection"] = rows;
    const DetectionTotals t = Totals(in.detection);
    if (t.with_truth) j["detection_rms_to_truth_px"] = t.rms_to_truth_px;
  }
  j["polynomial"] = PolynomialJson(r.polynomial, in.observations);
  const auto& u = r.unified;
  j["unified"] = {
      {"model", "unified_radtan"},
      {"xi", u.model.xi},
      {"fx", u.model.fx},
      {"fy", u.model.fy},
      {"cx", u.model.cx},
      {"cy", u.model.cy},
      {"distortion", {u.model.distortion.k1, u.model.distortion.k2, u.model.distortion.p1, u.model.distortion.p2}},
      {"board_flex", BoardFlexJson(r.polynomial.board_flex, u.board_warp, u.image_warps)},
      {"rms_px", u.rms},
      {"mean_px", u.mean},
      {"converged", u.converged},
      {"solver", u.solver_report},
      {"stddev", u.stddev},
      {"opencv_yaml", "unified.yaml"},
      {"board_poses", BoardPosesJson(u.cam_from_board, in.observations)}};
  nlohmann::json orders = nlohmann::json::array();
  for (const auto& o : r.orders)
    orders.push_back({{"degree", o.degree},
                      {"rms_px", o.rms_px},
                      {"mean_px", o.mean_px},
                      {"converged", o.converged},
                      {"per_image_mean_px", o.per_image_mean_px}});
  j["order_selection"] = orders;
  if (r.physical) {
    const auto& p = *r.physical;
    const double deg = 180 / M_PI;
    j["physical"] = {{"model", "physical (hyperboloid + camera pose, exact projection)"},
                     {"a", p.rig.mirror.a},
                     {"b", p.rig.mirror.b},
                     {"tilt_deg", {p.tilt.x() * deg, p.tilt.y() * deg, p.tilt.z() * deg}},
                     {"offset_m", {p.offset.x(), p.offset.y(), p.offset.z()}},
                     {"intrinsics_estimated", options.physical.estimate_intrinsics},
                     {"mirror_estimated", options.physical.estimate_mirror},
                     {"rms_px", p.rms},
                     {"converged", p.converged},
                     {"solver", p.solver_report},
                     {"rim_points", static_cast<int>(r.rim_points)},
                     {"rim_rms_px", p.rim_rms}};
  }
  if (r.cross_validation) j["cross_validation"] = CrossValidationJson(*r.cross_validation);
  if (r.polynomial_uncertainty) j["uncertainty"]["polynomial"] = UncertaintyJson(*r.polynomial_uncertainty);
  if (r.unified_uncertainty) j["uncertainty"]["unified"] = UncertaintyJson(*r.unified_uncertainty);
  if (r.suggestions) j["suggested_boards"] = SuggestionsJson(*r.suggestions);
  if (r.omnidir) {
    const auto& cv = *r.omnidir;
    j["opencv_omnidir"] = cv.ok ? nlohmann::json{{"rms_px", cv.rms},
                                                 {"opencv_reported_rms", cv.opencv_rms},
                                                 {"images_used", cv.images_used},
                                                 {"xi", cv.xi},
                                                 {"fx", cv.fx},
                                                 {"fy", cv.fy},
                                                 {"cx", cv.cx},
                                                 {"cy", cv.cy}}
                                : nlohmann::json{{"error", cv.error}};
  }
  if (in.truth) {
    const auto& rig = *in.truth;
    if (r.physical_vs_truth) {
      const auto& g = *r.physical_vs_truth;
      j["physical"]["ground_truth"] = {{"mean_ray_angle_deg", g.pixels ? nlohmann::json(g.mean_deg) : nlohmann::json()},
                                       {"max_ray_angle_deg", g.pixels ? nlohmann::json(g.max_deg) : nlohmann::json()},
                                       {"tilt_error_deg", g.tilt_error_deg},
                                       {"camera_centre_error_m", g.centre_error_m},
                                       {"pixels", g.pixels},
                                       {"true_a", rig.mirror.a},
                                       {"true_b", rig.mirror.b},
                                       {"note", "over the whole mirror image, points at 2 m, mirror frame"}};
    }
    // No pixel to compare (the model's annulus misses the true mirror image): no figure, not a zero.
    const auto& g = *r.polynomial_vs_truth;
    const auto figure = [&](double v) { return g.pixels ? nlohmann::json(v) : nlohmann::json(); };
    j["ground_truth"] = {{"mean_ray_angle_deg", figure(g.mean_deg)},
                         {"max_ray_angle_deg", figure(g.max_deg)},
                         {"pixels", g.pixels},
                         {"mean_ray_angle_aligned_deg", figure(g.mean_aligned_deg)},
                         {"max_ray_angle_aligned_deg", figure(g.max_aligned_deg)},
                         {"frame_rotation_deg", g.frame_rotation_deg},
                         {"true_centre", {rig.camera.cx, rig.camera.cy}}};
  }
  return j;
}

std::string MonoCalibrationSummary(const CalibrationInput& in, const MonoCalibration& r) {
  std::string s = "hovs calibrate: " + std::to_string(in.observations.size()) + " images\n";
  if (!in.detection.empty()) {
    const DetectionTotals t = Totals(in.detection);
    s += "  detection: board in " + std::to_string(in.observations.size()) + " of " +
         std::to_string(in.detection.size()) + " images (" + std::to_string(t.complete) + " complete), " +
         std::to_string(t.corners) + " corners (" + std::to_string(t.from_edges) + " from the board's edges)";
    if (t.with_truth) s += ", RMS " + FormatNumber("%.4f", t.rms_to_truth_px) + " px from the exact corners";
    s += "\n";
  }
  const auto& p = r.polynomial;
  s += "  polynomial (degree " + std::to_string(p.model.Degree()) + "): RMS " + FormatNumber("%.4f", p.rms) +
       " px, mean " + FormatNumber("%.4f", p.mean) + " px (linear start " + FormatNumber("%.3f", p.initial_rms) +
       " px)\n";
  if (!p.outliers.empty()) {
    s += "  rejected " + std::to_string(p.outliers.size()) + " corners above " +
         FormatNumber("%.3f", p.outlier_threshold_px) + " px:";
    for (const auto& ol : p.outliers)
      s += " " + ol.image + "#" + std::to_string(ol.corner) + " (" + FormatNumber("%.2f", ol.residual_px) + ")";
    s += "\n";
  }
  if (p.model.HasDecentering())
    s += "  decentering: p1 " + FormatNumber("%.3g", p.model.p1) + ", p2 " + FormatNumber("%.3g", p.model.p2) +
         " (hovs' extension of the model: in calibration.json only; OCamCalib's calib_results.txt cannot hold it)\n";
  if (p.board_flex)
    s += std::string(p.image_warps.empty() ? "  board flex: " : "  board flex (mean of the images'): ") +
         FormatNumber("%.3f", 1e3 * p.board_warp[0]) + " mm along x, " + FormatNumber("%.3f", 1e3 * p.board_warp[1]) +
         " mm along y (" + FormatNumber("%.3f", 1e3 * (p.board_warp[0] + p.board_warp[1])) + " mm at the centre)\n";
  s += "  unified + radtan:         RMS " + FormatNumber("%.4f", r.unified.rms) + " px\n";
  if (r.omnidir && r.omnidir->ok)
    s += "  OpenCV omnidir (same corners): RMS " + FormatNumber("%.4f", r.omnidir->rms) + " px\n";
  if (r.cross_validation) {
    const auto& cv = *r.cross_validation;
    s += "  cross-validation (" + std::to_string(cv.folds) + " folds): held-out RMS " +
         FormatNumber("%.4f", cv.held_out_rms) + " px (fit " + FormatNumber("%.4f", cv.train_rms) +
         " px); the folds' models differ from the full one by " + FormatNumber("%.3f", cv.spread.px_stats.median) +
         " px median, " + FormatNumber("%.3f", cv.spread.px_stats.p95) + " px 95 %\n";
  }
  for (const auto& [name, map] :
       {std::pair{"polynomial", &r.polynomial_uncertainty}, std::pair{"unified", &r.unified_uncertainty}})
    if (*map)
      s += std::string("  projection uncertainty (") + name + ", 1 sigma, " +
           ((*map)->range_m > 0 ? FormatNumber("%.3g", (*map)->range_m) + " m" : std::string("infinity")) +
           "): median " + FormatNumber("%.3f", (*map)->px_stats.median) + " px, 95 % " +
           FormatNumber("%.3f", (*map)->px_stats.p95) + " px; ray median " +
           FormatNumber("%.4f", (*map)->deg_stats.median) + " deg\n";
  if (r.suggestions) {
    s += "  next boards (the polynomial model's mean uncertainty over the field now " +
         FormatNumber("%.3f", r.suggestions->mean_px_now) + " px):\n";
    for (const auto& b : r.suggestions->boards)
      s += "    centre at pixel (" + FormatNumber("%.0f", b.centre_px.x()) + ", " +
           FormatNumber("%.0f", b.centre_px.y()) + "): azimuth " + FormatNumber("%.0f", b.azimuth_deg) +
           " deg, elevation " + FormatNumber("%.1f", b.elevation_deg) + " deg, " + FormatNumber("%.2f", b.distance_m) +
           " m, tilted " + FormatNumber("%.0f", b.tilt_deg) + " deg -> " + FormatNumber("%.3f", b.mean_px) + " px\n";
  }
  if (r.polynomial_vs_truth && r.polynomial_vs_truth->pixels == 0)
    s += "  vs ground truth: no pixel of the model's annulus sees the true mirror; nothing to compare\n";
  else if (r.polynomial_vs_truth)
    s += "  vs ground truth: mean ray angle " + FormatNumber("%.5f", r.polynomial_vs_truth->mean_deg) + " deg; " +
         FormatNumber("%.5f", r.polynomial_vs_truth->mean_aligned_deg) + " deg after removing a frame rotation of " +
         FormatNumber("%.4f", r.polynomial_vs_truth->frame_rotation_deg) + " deg\n";
  if (r.physical) {
    const auto& ph = *r.physical;
    s += "  physical model: RMS " + FormatNumber("%.4f", ph.rms) + " px, a " + FormatNumber("%.5f", ph.rig.mirror.a) +
         " m, b " + FormatNumber("%.5f", ph.rig.mirror.b) + " m, tilt (" +
         FormatNumber("%.3f", ph.tilt.x() * 180 / M_PI) + ", " + FormatNumber("%.3f", ph.tilt.y() * 180 / M_PI) +
         ") deg, offset (" + FormatNumber("%.2f", ph.offset.x() * 1e3) + ", " +
         FormatNumber("%.2f", ph.offset.y() * 1e3) + ", " + FormatNumber("%.2f", ph.offset.z() * 1e3) + ") mm" +
         (r.rim_points
              ? ", rim " + std::to_string(r.rim_points) + " points (RMS " + FormatNumber("%.3f", ph.rim_rms) + " px)"
              : "") +
         "\n";
    if (r.physical_vs_truth && r.physical_vs_truth->pixels)
      s += "  physical model vs ground truth: mean ray angle " + FormatNumber("%.5f", r.physical_vs_truth->mean_deg) +
           " deg\n";
  }
  for (size_t i = 0; i < in.observations.size(); ++i)
    if (p.per_image_mean[i] > 5.0) s += "  POOR: " + in.observations[i].image + " mean error above 5 px\n";
  return s;
}

void CornerAnnulus(const MonoCalibration& r, double* min_radius, double* max_radius) {
  double rmin = HUGE_VAL, rmax = 0;
  for (const auto& ob : r.inliers)
    for (const auto& p : ob.pixels) {
      const double rad = (p - Vec2d(r.unified.model.cx, r.unified.model.cy)).norm();
      rmin = std::min(rmin, rad), rmax = std::max(rmax, rad);
    }
  *min_radius = 0.9 * rmin, *max_radius = 1.05 * rmax;
}

}  // namespace hovs::calib
