#include "depth/stereo_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "io/image_io.h"
#include "results/html.h"
#include "results/plot.h"

namespace hovs::depth {
namespace {
namespace fs = std::filesystem;

nlohmann::json PoseJson(const Rigid3d& p) {
  const auto& q = p.rotation;
  const Vec3d& t = p.translation;
  return {{"q", {q.w(), q.x(), q.y(), q.z()}}, {"t", {t.x(), t.y(), t.z()}}};
}

// The reprojection figure of one pair and unit (the article's Fig. 28): a crop of the catadioptric image around
// the board, detected corners (green circles), reprojected corners (red crosses) and the residual magnified 20
// times (yellow).
void ReprojectionFigure(const fs::path& image, const std::vector<CornerObservation>& corners, const AnyModel& model,
                        const Rigid3d& mirror_from_board, const std::map<int, Vec3d>& board, const std::string& title,
                        const fs::path& out) {
  const io::Image8Bits im = io::ReadImage8(image);
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& p : corners)
    x0 = std::min(x0, p.pixel.x()), x1 = std::max(x1, p.pixel.x()), y0 = std::min(y0, p.pixel.y()),
    y1 = std::max(y1, p.pixel.y());
  const cv::Rect roi = cv::Rect(cv::Point(int(x0) - 40, int(y0) - 40), cv::Point(int(x1) + 40, int(y1) + 40)) &
                       cv::Rect(0, 0, im.width, im.height);
  cv::Mat full(im.height, im.width, im.channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<uint8_t*>(im.data.data()));
  cv::Mat crop;
  cv::cvtColor(full(roi), crop, im.channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_GRAY2BGR);
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
  cv::putText(crop, title, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
  cv::putText(crop, title, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  HOVS_REQUIRE(cv::imwrite(out.string(), crop), out.string(), "cannot write the figure");
}

// OpenCV FileStorage with stereoCalibrate's names: R, T.
void WriteOpenCvYaml(const fs::path& path, const StereoCalibration& c) {
  cv::FileStorage fs(path.string(), cv::FileStorage::WRITE);
  HOVS_REQUIRE(fs.isOpened(), path.string(), "cannot write");
  const Mat3<double> R = c.right_from_left.rotation.toRotationMatrix();
  cv::Mat Rm(3, 3, CV_64F), Tm(3, 1, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) Rm.at<double>(r, k) = R(r, k);
    Tm.at<double>(r) = c.right_from_left.translation(r);
  }
  fs << "R" << Rm << "T" << Tm << "baseline" << c.baseline << "sigma_baseline" << c.sigma_baseline << "rms_px"
     << c.rms_px << "frames"
     << "right mirror frame from left mirror frame, metres";
}

// |relative depth error| (%) of every sparse point against its range and against its angle to the baseline, the
// conditioned points (at least kConditionedAngleDeg from the baseline) apart from the others.
void SparseDepthPlots(const SparseDepthEvaluation& e, const fs::path& folder) {
  results::Series cond{"at least 15 deg from the baseline", {}, {}, {0.1, 0.3, 0.8}, 1.0, true, 4.0};
  results::Series near{"within 15 deg of the baseline", {}, {}, {0.85, 0.2, 0.1}, 1.0, true, 4.0};
  results::Series cond_a = cond, near_a = near;
  for (const auto& p : e.points) {
    const bool ok =
        p.angle_to_baseline_deg >= kConditionedAngleDeg && p.angle_to_baseline_deg <= 180 - kConditionedAngleDeg;
    auto& by_range = ok ? cond : near;
    auto& by_angle = ok ? cond_a : near_a;
    by_range.x.push_back(p.range_m), by_range.y.push_back(100 * std::abs(p.rel_error));
    by_angle.x.push_back(p.angle_to_baseline_deg), by_angle.y.push_back(100 * std::abs(p.rel_error));
  }
  const auto plot = [&](const std::string& title, const std::string& x_label, results::Series a, results::Series b,
                        const fs::path& path) {
    results::LineFigure f;
    f.title = title, f.x_label = x_label, f.y_label = "|relative depth error| (%)";
    for (auto* s : {&a, &b})
      if (!s->x.empty()) f.series.push_back(*s);
    results::WritePng(f, path);
  };
  plot("Sparse depth error against range", "true range from the left viewpoint (m)", cond, near,
       folder / "depth_error_vs_range.png");
  plot("Sparse depth error against the angle to the baseline", "angle between the point and the baseline (deg)", cond_a,
       near_a, folder / "depth_error_vs_angle.png");
}

}  // namespace

StereoRun RunStereoCalibration(const StereoDataset& dataset, const AnyModel& left, const AnyModel& right,
                               std::vector<StereoPairObservation> pairs, std::vector<PairDetection> detections,
                               const StereoCalibrationOptions& options, const std::string& corner_refinement) {
  StereoRun r;
  r.dataset = &dataset, r.left = &left, r.right = &right;
  r.pairs = std::move(pairs), r.detections = std::move(detections);
  r.options = options, r.corner_refinement = corner_refinement;
  r.calibration = CalibrateStereo(left, right, r.pairs, dataset.board, options);
  // The article's method on the same detections, for comparison: each unit's board pose on its own, then the
  // relative pose from the 3-D residual alone.
  try {
    StereoCalibrationOptions s3 = options;
    s3.residual = "3d";
    r.article_3d = CalibrateStereo(left, right, r.pairs, dataset.board, s3);
  } catch (const Error& e) { r.article_3d_error = e.what(); }
  // Against the true rig. With calibrated models the relative pose is that of the models' frames, which for
  // these units coincide with the mirror frames up to the calibration's error.
  const Rigid3d truth = dataset.TrueRightFromLeft();
  r.pose_error = CompareWithTruth(r.calibration.right_from_left, r.calibration.baseline, truth);
  if (r.article_3d)
    r.article_3d_pose_error = CompareWithTruth(r.article_3d->right_from_left, r.article_3d->baseline, truth);
  r.sparse = EvaluateSparseDepth(dataset, left, right, r.calibration, r.pairs);
  return r;
}

nlohmann::json StereoRunJson(const StereoRun& r) {
  const StereoCalibration& c = r.calibration;
  nlohmann::json per = nlohmann::json::array();
  for (size_t k = 0; k < c.pair_names.size(); ++k)
    per.push_back({{"pair", c.pair_names[k]},
                   {"rms_left_px", c.pair_rms_left_px[k]},
                   {"rms_right_px", c.pair_rms_right_px[k]},
                   {"corners_left", c.pair_corners_left[k]},
                   {"corners_right", c.pair_corners_right[k]},
                   {"above_10px", std::max(c.pair_rms_left_px[k], c.pair_rms_right_px[k]) > 10}});
  nlohmann::json det = nlohmann::json::array();
  for (const auto& d : r.detections)
    det.push_back({{"pair", d.pair},
                   {"left_corners", d.left_corners},
                   {"right_corners", d.right_corners},
                   {"left_from_edges", d.left_from_edges},
                   {"right_from_edges", d.right_from_edges},
                   {"inconsistent_markers_left", d.inconsistent_left},
                   {"inconsistent_markers_right", d.inconsistent_right}});
  nlohmann::json j = {
      {"models", {r.left->KindName(), r.right->KindName()}},
      {"right_from_left", PoseJson(c.right_from_left)},
      {"baseline_m", c.baseline},
      {"sigma_baseline_m", c.sigma_baseline},
      {"sigma_translation_m", {c.sigma_translation.x(), c.sigma_translation.y(), c.sigma_translation.z()}},
      {"sigma_rotation_deg", {c.sigma_rotation_deg.x(), c.sigma_rotation_deg.y(), c.sigma_rotation_deg.z()}},
      {"rms_px", c.rms_px},
      {"converged", c.converged},
      {"solver", c.solver_report},
      {"pairs", per},
      {"detections", det}};
  nlohmann::json outl = nlohmann::json::array();
  for (const auto& x : c.outliers)
    outl.push_back({{"pair", x.pair}, {"unit", x.unit}, {"corner", x.corner}, {"residual_px", x.residual_px}});
  j["outliers"] = {{"threshold_px", r.options.outlier_px}, {"dropped", outl}};
  j["corner_refinement"] = r.corner_refinement;
  const auto pose_error = [](const PoseError& e) {
    return nlohmann::json{{"baseline_error_mm", e.baseline_error_mm},
                          {"translation_error_mm", e.translation_error_mm},
                          {"rotation_error_deg", e.rotation_error_deg}};
  };
  if (r.article_3d) {
    j["article_3d_residual"] = {
        {"method", "per-unit board poses, then right_from_left from T P_left - P_right (the article's 3.2.2)"},
        {"right_from_left", PoseJson(r.article_3d->right_from_left)},
        {"baseline_m", r.article_3d->baseline},
        {"rms_3d_mm", 1e3 * r.article_3d->rms_3d_m},
        {"rms_px", r.article_3d->rms_px},
        {"converged", r.article_3d->converged},
        {"ground_truth", pose_error(r.article_3d_pose_error)}};
  } else {
    j["article_3d_residual"] = {{"error", r.article_3d_error}};
  }
  j["ground_truth"] = pose_error(r.pose_error);
  j["ground_truth"]["baseline_m"] = r.pose_error.true_baseline_m;
  const nlohmann::json sparse = SparseDepthJson(r.sparse);
  if (!sparse.is_null()) j["sparse_depth"] = sparse;
  return j;
}

std::string StereoRunSummary(const StereoRun& r) {
  const StereoCalibration& c = r.calibration;
  std::string s = "hovs stereo-calibrate: " + std::to_string(c.pair_names.size()) + " pairs, baseline " +
                  std::to_string(c.baseline) + " m (sigma " + std::to_string(c.sigma_baseline * 1e3) + " mm), RMS " +
                  std::to_string(c.rms_px) + " px, " + std::to_string(c.outliers.size()) +
                  " outlier corners dropped (listed in stereo.json)\n";
  char line[200];
  std::snprintf(line, sizeof line, "  against the true rig: baseline error %.3f mm, rotation error %.4f deg\n",
                r.pose_error.baseline_error_mm, r.pose_error.rotation_error_deg);
  s += line;
  if (r.article_3d) {
    std::snprintf(line, sizeof line,
                  "  the article's 3-D residual method on the same corners: baseline error %.3f mm, rotation error "
                  "%.4f deg, reprojection RMS %.3f px\n",
                  r.article_3d_pose_error.baseline_error_mm, r.article_3d_pose_error.rotation_error_deg,
                  r.article_3d->rms_px);
    s += line;
  }
  const nlohmann::json sparse = SparseDepthJson(r.sparse);
  if (sparse.is_null()) return s;
  if (sparse.contains("conditioned")) {
    std::snprintf(line, sizeof line, "  of them %zu at least %.0f deg from the baseline: worst %.3f %%\n",
                  sparse["conditioned"]["points"].get<size_t>(), kConditionedAngleDeg,
                  100 * sparse["conditioned"]["max_rel_error"].get<double>());
    s += line;
  }
  std::snprintf(line, sizeof line, "  sparse depth of %zu marker corners: RMS %.3f %%, worst %.3f %%\n",
                r.sparse.points.size(), 100 * sparse["rms_rel_error"].get<double>(),
                100 * sparse["max_rel_error"].get<double>());
  s += line;
  return s;
}

void WriteStereoReport(const fs::path& folder, const StereoRun& r, const nlohmann::json& record) {
  const StereoCalibration& c = r.calibration;
  const StereoDataset& d = *r.dataset;
  fs::create_directories(folder / "figures");
  results::HtmlPage page("hovs stereo calibration");
  const std::string summary = StereoRunSummary(r);
  page.Preformatted(summary);
  std::vector<std::vector<std::string>> rows;
  for (size_t k = 0; k < c.pair_names.size(); ++k)
    rows.push_back({c.pair_names[k], std::to_string(c.pair_corners_left[k]),
                    FormatNumber("%.3f", c.pair_rms_left_px[k]), std::to_string(c.pair_corners_right[k]),
                    FormatNumber("%.3f", c.pair_rms_right_px[k])});
  page.Heading("Pairs");
  page.Table({"pair", "corners, left", "RMS left (px)", "corners, right", "RMS right (px)"}, rows);
  if (!r.sparse.points.empty()) {
    WriteFileAtomic(folder / "sparse_depth.csv", SparseDepthCsv(r.sparse));
    page.Heading("Sparse depth against the true range");
    if (results::CanRender()) {
      SparseDepthPlots(r.sparse, folder / "figures");
      page.Figure("figures/depth_error_vs_range.png", "|relative error| against range", 640);
      page.Figure("figures/depth_error_vs_angle.png",
                  "|relative error| against the angle to the baseline: near "
                  "0 and 180 deg a pixel of disparity is a large part of the range",
                  640);
    } else {
      page.Paragraph("No plots: no X display (run under xvfb-run -a). The points are in sparse_depth.csv.");
    }
    page.Link("Every point: ", "sparse_depth.csv", "sparse_depth.csv", ".");
  }
  page.Heading("Reprojection (residuals x20)");
  for (size_t k = 0; k < c.pair_names.size(); ++k) {
    const auto& name = c.pair_names[k];
    const auto& obs = *std::find_if(r.pairs.begin(), r.pairs.end(), [&](const auto& p) { return p.name == name; });
    const auto& frame = *std::find_if(d.frames.begin(), d.frames.end(), [&](const auto& f) { return f.name == name; });
    for (int side = 0; side < 2; ++side) {
      const auto& corners = side == 0 ? obs.left : obs.right;
      if (corners.empty()) continue;
      const std::string unit = side == 0 ? d.left_unit.name : d.right_unit.name;
      char title[160];
      std::snprintf(title, sizeof title, "%s %s: RMS %.3f px, %zu corners (residuals x20)", name.c_str(), unit.c_str(),
                    side == 0 ? c.pair_rms_left_px[k] : c.pair_rms_right_px[k], corners.size());
      const std::string fig = "figures/" + name + "_" + unit + ".png";
      ReprojectionFigure(side == 0 ? frame.left_image : frame.right_image, corners, side == 0 ? *r.left : *r.right,
                         side == 0 ? c.left_from_board[k] : c.right_from_left * c.left_from_board[k], d.board, title,
                         folder / fig);
      if (k == 0) page.Figure(fig, title, 420);
    }
  }
  page.Heading("Files");
  page.Link("Every figure, the solver report and the outliers: ", "stereo.json", "stereo.json", ".");
  page.Link("R and T in OpenCV's format: ", "stereo.yaml", "stereo.yaml", ".");
  WriteFileAtomic(folder / "stereo.json", record.dump(1));
  WriteOpenCvYaml(folder / "stereo.yaml", c);
  WriteFileAtomic(folder / "summary.txt", summary);
  WriteFileAtomic(folder / "index.html", page.Render());
}

}  // namespace hovs::depth
