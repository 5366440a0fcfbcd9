// The report folder of a monocular calibration: its files, the article's figures 19 and 20, and the page.
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calib/mono_calibration.h"
#include "calib/ocam_io.h"
#include "calib/omnidir_io.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "results/html.h"

namespace hovs::calib {
namespace {

// The reprojection figure of one image (the article's Fig. 19): a crop around the board, detected corners (green
// circles; rejected corners large magenta), the polynomial model's reprojections (red crosses) and the
// residuals magnified 20 times (yellow).
void ReprojectionFigure(const std::filesystem::path& image, const BoardObservation& ob, const std::vector<bool>& inlier,
                        const PolynomialModel<double>& model, const Rigid3d& cam_from_board, double rms,
                        const std::filesystem::path& out) {
  const cv::Mat grey = ReadGreyImage(image);
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& p : ob.pixels)
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  const cv::Rect roi = cv::Rect(cv::Point(int(x0) - 30, int(y0) - 30), cv::Point(int(x1) + 30, int(y1) + 30)) &
                       cv::Rect(0, 0, grey.cols, grey.rows);
  cv::Mat crop;
  cv::cvtColor(grey(roi), crop, cv::COLOR_GRAY2BGR);
  const double scale = 600.0 / std::max(roi.width, roi.height);
  cv::resize(crop, crop, cv::Size(), scale, scale, cv::INTER_CUBIC);
  const auto at = [&](const Vec2d& p) {
    return cv::Point2d((p.x() - roi.x + 0.5) * scale - 0.5, (p.y() - roi.y + 0.5) * scale - 0.5);
  };
  for (size_t k = 0; k < ob.pixels.size(); ++k) {
    Vec2d uv;
    const bool in = k >= inlier.size() || inlier[k];
    cv::circle(crop, at(ob.pixels[k]), in ? 5 : 9, in ? cv::Scalar(0, 200, 0) : cv::Scalar(255, 0, 255), in ? 1 : 2,
               cv::LINE_AA);
    if (!model.ImgFromCam(cam_from_board * ob.board_points[k], &uv)) continue;
    cv::drawMarker(crop, at(uv), cv::Scalar(0, 0, 255), cv::MARKER_CROSS, 8, 1, cv::LINE_AA);
    cv::line(crop, at(ob.pixels[k]), at(ob.pixels[k] + 20 * (uv - ob.pixels[k])), cv::Scalar(0, 220, 255), 1,
             cv::LINE_AA);
  }
  char text[200];
  const size_t rejected = std::count(inlier.begin(), inlier.end(), false);
  std::snprintf(text, sizeof text, "%s: RMS %.3f px, %zu corners%s (residuals x20)", ob.image.c_str(), rms,
                ob.pixels.size(), rejected ? (", " + std::to_string(rejected) + " rejected (magenta)").c_str() : "");
  cv::putText(crop, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
  cv::putText(crop, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  HOVS_REQUIRE(cv::imwrite(out.string(), crop), out.string(), "cannot write the figure");
}

// The suggested boards drawn through the model on the first image (or a grey canvas): each board's squares
// filled black and white where the model puts them, numbered; the calibration's corners as small green dots.
void SuggestionFigure(const CalibrationInput& in, const Suggestions& s, const std::filesystem::path& out) {
  cv::Mat fig;
  if (!in.paths.empty()) {
    cv::cvtColor(ReadGreyImage(in.paths[0]) / 2 + 64, fig, cv::COLOR_GRAY2BGR);
  } else {
    fig = cv::Mat(in.height, in.width, CV_8UC3, cv::Scalar(128, 128, 128));
  }
  for (const auto& o : in.observations)
    for (const auto& p : o.pixels) cv::circle(fig, cv::Point2d(p.x(), p.y()), 1, cv::Scalar(0, 200, 0), -1);
  // The board's grid: square size and each corner's (column, row).
  double square = HUGE_VAL;
  const auto& P = s.board_points;
  for (size_t a = 0; a < P.size(); ++a)
    for (size_t b = a + 1; b < P.size(); ++b) square = std::min(square, (P[a] - P[b]).norm());
  std::map<std::pair<long, long>, size_t> at;
  for (size_t k = 0; k < P.size(); ++k) at[{std::lround(P[k].x() / square), std::lround(P[k].y() / square)}] = k;
  for (size_t n = 0; n < s.boards.size(); ++n) {
    const auto& c = s.boards[n].corners_px;
    for (const auto& [ij, k] : at) {
      const auto right = at.find({ij.first + 1, ij.second}), down = at.find({ij.first, ij.second + 1}),
                 diag = at.find({ij.first + 1, ij.second + 1});
      if (right == at.end() || down == at.end() || diag == at.end()) continue;
      std::vector<cv::Point> quad;
      for (size_t q : {k, right->second, diag->second, down->second})
        quad.emplace_back(static_cast<int>(std::lround(c[q].x())), static_cast<int>(std::lround(c[q].y())));
      const bool dark = (ij.first + ij.second) % 2 == 0;
      cv::fillConvexPoly(fig, quad, dark ? cv::Scalar(20, 20, 20) : cv::Scalar(240, 240, 240), cv::LINE_AA);
    }
    const cv::Point label(static_cast<int>(s.boards[n].centre_px.x()) - 8,
                          static_cast<int>(s.boards[n].centre_px.y()) + 8);
    cv::putText(fig, std::to_string(n + 1), label, cv::FONT_HERSHEY_SIMPLEX, 0.9, cv::Scalar(255, 255, 255), 4,
                cv::LINE_AA);
    cv::putText(fig, std::to_string(n + 1), label, cv::FONT_HERSHEY_SIMPLEX, 0.9, cv::Scalar(0, 0, 255), 2,
                cv::LINE_AA);
  }
  if (fig.cols > 1200) cv::resize(fig, fig, cv::Size(), 1200.0 / fig.cols, 1200.0 / fig.cols, cv::INTER_AREA);
  HOVS_REQUIRE(cv::imwrite(out.string(), fig), out.string(), "cannot write the figure");
}

// The article's Fig. 20 (OCamCalib's error plot): every corner's reprojection error (du, dv), one colour per
// image, rejected corners as crosses; beside it, where in the image the errors are (colour = error length).
void ErrorMapFigure(const std::vector<BoardObservation>& obs, const PolynomialCalibration& cal,
                    const std::filesystem::path& out) {
  const int S = 520, W = 2 * S + 20;
  cv::Mat fig(S + 40, W, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<std::vector<Vec2d>> res(obs.size());
  double extent = 0, worst_in = 0;
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t k = 0; k < obs[i].pixels.size(); ++k) {
      Vec2d uv(1e9, 1e9);
      cal.model.ImgFromCam(
          cal.cam_from_board[i] * cal.board_extent.Warped<double>(obs[i].board_points[k], cal.WarpOf(i).data()), &uv);
      res[i].push_back(uv - obs[i].pixels[k]);
      const bool in = cal.inlier.empty() || cal.inlier[i][k];
      extent = std::max(extent, res[i].back().cwiseAbs().maxCoeff());
      if (in) worst_in = std::max(worst_in, res[i].back().norm());
    }
  extent = std::max(1e-3, std::min(extent, 4 * worst_in + 1e-3));
  // A round axis limit: 1, 2 or 5 times a power of ten.
  double lim = std::pow(10, std::floor(std::log10(extent)));
  for (double f : {1.0, 2.0, 5.0, 10.0})
    if (f * lim >= extent) {
      lim *= f;
      break;
    }
  const auto put = [&](const std::string& t, cv::Point p, double sc = 0.45) {
    cv::putText(fig, t, p, cv::FONT_HERSHEY_SIMPLEX, sc, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  };
  const cv::Rect left(40, 20, S - 40, S - 40);
  cv::rectangle(fig, left, cv::Scalar(0, 0, 0));
  const auto at = [&](const Vec2d& r) {
    return cv::Point2d(left.x + (r.x() / lim + 1) * 0.5 * left.width, left.y + (r.y() / lim + 1) * 0.5 * left.height);
  };
  cv::line(fig, at(Vec2d(-lim, 0)), at(Vec2d(lim, 0)), cv::Scalar(200, 200, 200));
  cv::line(fig, at(Vec2d(0, -lim)), at(Vec2d(0, lim)), cv::Scalar(200, 200, 200));
  char buf[120];
  std::snprintf(buf, sizeof buf, "%.3g", lim);
  put(buf, cv::Point(left.br().x - 30, left.br().y + 15));
  put("-" + std::string(buf), cv::Point(left.x - 10, left.br().y + 15));
  put("du (px)", cv::Point(left.x + left.width / 2 - 20, left.br().y + 15));
  put("dv (px), down", cv::Point(left.x, left.y - 6));
  cv::Mat hue(1, static_cast<int>(std::max<size_t>(obs.size(), 1)), CV_8UC3);
  for (int i = 0; i < hue.cols; ++i)
    hue.at<cv::Vec3b>(0, i) = cv::Vec3b(static_cast<uchar>(170 * i / std::max(1, hue.cols)), 230, 210);
  cv::cvtColor(hue, hue, cv::COLOR_HSV2BGR);
  for (size_t i = 0; i < obs.size(); ++i) {
    const cv::Vec3b c = hue.at<cv::Vec3b>(0, static_cast<int>(i));
    for (size_t k = 0; k < res[i].size(); ++k) {
      const Vec2d r = res[i][k].cwiseMax(Vec2d(-lim, -lim)).cwiseMin(Vec2d(lim, lim));
      if (cal.inlier.empty() || cal.inlier[i][k])
        cv::circle(fig, at(r), 2, cv::Scalar(c[0], c[1], c[2]), cv::FILLED, cv::LINE_AA);
      else
        cv::drawMarker(fig, at(r), cv::Scalar(c[0], c[1], c[2]), cv::MARKER_TILTED_CROSS, 9, 2, cv::LINE_AA);
    }
  }
  // Right: positions in the image, colour = |error| on a 0..lim scale.
  const double sc = (S - 40.0) / std::max(cal.model.width, cal.model.height);
  const cv::Rect right(S + 20, 20, static_cast<int>(cal.model.width * sc), static_cast<int>(cal.model.height * sc));
  cv::rectangle(fig, right, cv::Scalar(0, 0, 0));
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int k = 0; k < 256; ++k) ramp.at<uchar>(0, k) = static_cast<uchar>(k);
  cv::applyColorMap(ramp, ramp, cv::COLORMAP_TURBO);
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t k = 0; k < res[i].size(); ++k) {
      const int idx = static_cast<int>(std::clamp(res[i][k].norm() / lim, 0.0, 1.0) * 255);
      const cv::Vec3b c = ramp.at<cv::Vec3b>(0, idx);
      cv::circle(fig,
                 cv::Point2d(right.x + (obs[i].pixels[k].x() + 0.5) * sc, right.y + (obs[i].pixels[k].y() + 0.5) * sc),
                 3, cv::Scalar(c[0], c[1], c[2]), cv::FILLED, cv::LINE_AA);
    }
  cv::resize(ramp, ramp, cv::Size(200, 10), 0, 0, cv::INTER_NEAREST);
  ramp.copyTo(fig(cv::Rect(right.x, S + 10, 200, 10)));
  put("|error| 0 .. " + std::string(buf) + " px", cv::Point(right.x + 210, S + 20));
  std::snprintf(buf, sizeof buf, "reprojection errors: %zu images, RMS %.3f px, %zu rejected", obs.size(), cal.rms,
                cal.outliers.size());
  put(buf, cv::Point(40, S + 20));
  HOVS_REQUIRE(cv::imwrite(out.string(), fig), out.string(), "cannot write the figure");
}

}  // namespace

void WriteMonoCalibrationReport(const std::filesystem::path& folder, const CalibrationInput& in,
                                const MonoCalibration& r, const nlohmann::json& record) {
  WriteFileAtomic(folder / "calibration.json", record.dump(2) + "\n");
  // OCamCalib's files hold its own model only: a model with decentering is in calibration.json alone.
  const bool ocam = !r.polynomial.model.HasDecentering();
  if (ocam) {
    WriteFileAtomic(folder / "calib_results.txt", FormatOcamCalibResults(r.polynomial.model));
    OcamExtrinsics extrinsics;
    for (size_t i = 0; i < r.polynomial.cam_from_board.size() && i < in.observations.size(); ++i)
      extrinsics.images.push_back(in.observations[i].image),
          extrinsics.mirror_from_board.push_back(r.polynomial.cam_from_board[i]);
    WriteFileAtomic(folder / "calib_extrinsics.txt", FormatOcamExtrinsics(extrinsics));
  }
  OmnidirFile of;
  of.model = r.unified.model, of.rms_px = r.unified.rms, of.stddev = r.unified.stddev;
  of.cam_from_board = r.unified.cam_from_board;
  CornerAnnulus(r, &of.annulus_min, &of.annulus_max);
  WriteFileAtomic(folder / "unified.yaml", FormatOmnidirYaml(of));
  const std::string summary = MonoCalibrationSummary(in, r);
  WriteFileAtomic(folder / "summary.txt", summary);

  results::HtmlPage page("hovs calibration");
  page.Preformatted(summary);
  page.Heading("Per-image mean reprojection error by polynomial degree (px)");
  std::vector<std::string> header = {"image"};
  for (const auto& o : r.orders) header.push_back("N = " + std::to_string(o.degree));
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < in.observations.size(); ++i) {
    std::vector<std::string> row = {in.observations[i].image};
    for (const auto& o : r.orders) row.push_back(FormatNumber("%.4f", o.per_image_mean_px[i]));
    rows.push_back(row);
  }
  std::vector<std::string> all = {"all (RMS)"};
  for (const auto& o : r.orders) all.push_back(FormatNumber("%.4f", o.rms_px));
  rows.push_back(all);
  page.Table(header, rows);
  std::filesystem::create_directories(folder / "figures");
  const auto& p = r.polynomial;
  if (!in.paths.empty()) {
    page.Heading("Reprojection per image (polynomial model; residuals x20)");
    for (size_t i = 0; i < in.observations.size() && i < in.paths.size(); ++i) {
      const std::string fig = "figures/" + std::filesystem::path(in.observations[i].image).stem().string() + ".png";
      BoardObservation warped = in.observations[i];  // the board as the solve saw it (its flex, if estimated)
      warped.board_points = p.board_extent.Warped(warped.board_points, p.WarpOf(i));
      ReprojectionFigure(in.paths[i], warped, p.inlier[i], p.model, p.cam_from_board[i], p.per_image_rms[i],
                         folder / fig);
      page.Figure(fig, in.observations[i].image + ": RMS " + FormatNumber("%.3f", p.per_image_rms[i]) + " px", 420);
    }
  }
  ErrorMapFigure(in.observations, p, folder / "figures/error_map.png");
  page.Heading("Reprojection error map (polynomial model; the article's Fig. 20)");
  page.Figure("figures/error_map.png",
              "left: (du, dv) of every corner, one colour per image, rejected corners as "
              "crosses; right: where in the image, colour = error length",
              900);
  if (r.cross_validation) {
    const auto& cv = *r.cross_validation;
    WriteModelDiffFigures(cv.spread, "folds vs all images", folder / "figures/cross_validation_px.png",
                          folder / "figures/cross_validation_deg.png");
    page.Heading("Cross-validation (" + std::to_string(cv.folds) + " folds, polynomial model)");
    page.Paragraph("Held-out reprojection RMS " + FormatNumber("%.4f", cv.held_out_rms) +
                   " px (each held-out board "
                   "posed with its fold's model), against " +
                   FormatNumber("%.4f", cv.train_rms) +
                   " px on the images each fold was fitted to. The maps: per pixel, the RMS over the folds of the "
                   "difference between the fold's model and the model of all images, after the best rotation.");
    page.Figure("figures/cross_validation_px.png", "difference, pixels", 700);
    page.Figure("figures/cross_validation_deg.png", "difference, degrees", 700);
  }
  for (const auto& [name, map] : {std::pair{std::string("polynomial"), &r.polynomial_uncertainty},
                                  std::pair{std::string("unified"), &r.unified_uncertainty}}) {
    if (!*map) continue;
    const auto& m = **map;
    const std::string px = "figures/uncertainty_" + name + "_px.png", deg = "figures/uncertainty_" + name + "_deg.png";
    WriteUncertaintyFigures(m, name, folder / px, folder / deg);
    page.Heading("Projection uncertainty (" + name + " model)");
    page.Paragraph(
        "The spread of the projection of a fixed point that the corners' own noise (sigma " +
        FormatNumber("%.3f", m.sigma_px) +
        " px, from the residuals) leaves in the solution, propagated through the covariance of the intrinsics and "
        "every board pose (mrcal's method: the point is tied to the world by the mean of the boards' frames). "
        "Large where no board was seen. 1 sigma, worst direction; the ray map is the same at infinity in degrees.");
    page.Figure(px, "pixels", 700);
    page.Figure(deg, "ray, degrees", 700);
  }
  if (r.suggestions) {
    SuggestionFigure(in, *r.suggestions, folder / "figures/suggested_boards.png");
    page.Heading("Where to hold the board next");
    page.Paragraph("Of " + std::to_string(r.suggestions->candidates) +
                   " candidate poses that the polynomial model sees whole, the ones that lower its mean projection "
                   "uncertainty over the calibrated field most (chosen one after the other): from " +
                   FormatNumber("%.3f", r.suggestions->mean_px_now) + " px now to " +
                   FormatNumber("%.3f", r.suggestions->boards.back().mean_px) +
                   " px with all of them. Drawn through the model; green dots: the corners already used.");
    page.Figure("figures/suggested_boards.png", "suggested boards, numbered in order", 800);
  }
  page.Heading("Files");
  page.Link("Every figure above, the solver reports and the standard deviations: ", "calibration.json",
            "calibration.json", ".");
  if (ocam) {
    page.Link("The polynomial model in OCamCalib's format: ", "calib_results.txt", "calib_results.txt", ".");
    page.Link("Its board poses in OCamCalib's RRfin layout: ", "calib_extrinsics.txt", "calib_extrinsics.txt", ".");
  }
  page.Link("The unified model in OpenCV omnidir's format: ", "unified.yaml", "unified.yaml", ".");
  WriteFileAtomic(folder / "index.html", page.Render());
}

}  // namespace hovs::calib
