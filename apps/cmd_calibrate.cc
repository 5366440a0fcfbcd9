// hovs calibrate: monocular calibration from a corner table (e.g. shared/data/vmr), a dataset manifest
// (synthetic or real) or a folder of images. Corners come from hovs' checkerboard detector (every image gets a
// detection status; with ground truth, the detected corners are compared with the exact ones); with
// --truth-corners a synthetic manifest's exact corners are used instead (optionally with seeded noise) to check
// the solver alone. With a synthetic manifest the result is compared with the exact rig.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "calib/checkerboard_detector.h"
#include "calib/ocam_io.h"
#include "calib/omnidir_io.h"
#include "calib/omnidir_reference.h"
#include "calib/physical_calibration.h"
#include "calib/rim_positioning.h"
#include "scenes/scene_config.h"
#include "calib/polynomial_calibration.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "results/html.h"
#include "results/plot.h"
#include "scenes/ground_truth.h"

namespace hovs::apps {
namespace {

std::string F(const char* fmt, double v) {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

struct Input {
  std::vector<calib::BoardObservation> obs;
  int width = 0, height = 0;
  std::optional<raytrace::CatadioptricUnit> truth;  // synthetic datasets only
  nlohmann::json description;
  nlohmann::json detection = nlohmann::json::array();  // per image: status, corners, error against truth
  std::vector<std::filesystem::path> paths;              // image files of obs (detection modes)
};

// The reprojection figure of one image (the article's Fig. 19): a crop around the board, detected corners (green
// circles; rejected corners large magenta), the polynomial model's reprojections (red crosses) and the
// residuals magnified 20 times (yellow).
void ReprojectionFigure(const std::filesystem::path& image, const calib::BoardObservation& ob,
                        const std::vector<bool>& inlier, const PolynomialModel<double>& model,
                        const Rigid3d& cam_from_board, double rms, const std::filesystem::path& out);

cv::Mat GreyImage(const std::filesystem::path& path) {
  const unwrap::Image8 im = LoadImage8(path);
  cv::Mat m(im.height, im.width, im.channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<uint8_t*>(im.data.data()));
  cv::Mat grey;
  if (im.channels == 3) cv::cvtColor(m, grey, cv::COLOR_RGB2GRAY);
  else grey = m.clone();
  return grey;
}

// Runs the detector on one image; records its status (never drops an image silently). With ground-truth
// pixels, the detected corners are matched to the nearest true corner and the distances reported.
void DetectInto(const std::filesystem::path& path, const std::string& name, const calib::CheckerboardDetectOptions& o,
                const std::vector<Vec2d>* truth, Input* in, int* width, int* height) {
  const cv::Mat grey = GreyImage(path);
  if (*width == 0) *width = grey.cols, *height = grey.rows;
  HOVS_REQUIRE(grey.cols == *width && grey.rows == *height, path.string(), "image size ", grey.cols, "x", grey.rows,
               " differs from the first image's ", *width, "x", *height);
  const auto det = calib::DetectCheckerboard(grey, o);
  nlohmann::json row = {{"image", name}, {"status", det.status}, {"found", det.found}, {"complete", det.complete},
                        {"corners", det.pixels.size()}, {"from_edges", det.from_edges}, {"candidates", det.candidates},
                        {"corner_refinement", o.corner_refinement}};
  if (truth && det.found) {
    double ss = 0, worst = 0;
    for (const auto& p : det.pixels) {
      double best = 1e30;
      for (const auto& t : *truth) best = std::min(best, (t - p).norm());
      ss += best * best, worst = std::max(worst, best);
    }
    row["rms_to_truth_px"] = std::sqrt(ss / det.pixels.size());
    row["max_to_truth_px"] = worst;
  }
  in->detection.push_back(row);
  if (det.found) in->obs.push_back(calib::ToObservation(det, name)), in->paths.push_back(path);
}

calib::CheckerboardSpec ParseBoard(const std::string& text) {
  calib::CheckerboardSpec b;
  char x1 = 0, x2 = 0;
  int end = -1;   // where parsing stopped: nothing may follow (7x6x0.03x9 was read as 7x6x0.03)
  HOVS_REQUIRE(std::sscanf(text.c_str(), "%d%c%d%c%lf%n", &b.cols, &x1, &b.rows, &x2, &b.square, &end) == 5 &&
                   x1 == 'x' && x2 == 'x' && end == static_cast<int>(text.size()),
               "--board", "expected COLSxROWSxSQUARE (inner corners, square in metres), e.g. 7x6x0.03 (got '", text,
               "')");
  b.Check("--board");
  return b;
}

Input FromDataset(const std::filesystem::path& manifest, const std::string& unit_name, bool truth_corners,
                  double noise, uint64_t seed, const calib::CheckerboardDetectOptions& detect) {
  const auto m = LoadDatasetManifest(manifest);
  Input in;
  const auto dir = manifest.parent_path();
  int unit_index = -1;
  for (size_t u = 0; u < m["units"].size(); ++u)
    if (unit_name.empty() ? u == 0 : m["units"][u]["name"] == unit_name) unit_index = static_cast<int>(u);
  HOVS_REQUIRE(unit_index >= 0, manifest.string(), "no unit '", unit_name, "' in the manifest");
  const auto& uj = m["units"][unit_index];
  const bool synthetic = uj.contains("mirror");
  if (synthetic) {
    in.truth = scenes::UnitFromJson(uj, manifest.string() + " (units)");
    in.width = in.truth->rig.camera.width, in.height = in.truth->rig.camera.height;
  }
  calib::CheckerboardDetectOptions dopt = detect;
  if (m.contains("boards") && !m["boards"].empty() && JsonText(m["boards"][0], "type") == "checker") {
    const auto& b = m["boards"][0];
    try {
      dopt.board.cols = b.at("inner_corners").at(0), dopt.board.rows = b.at("inner_corners").at(1);
      dopt.board.square = b.at("square");
    } catch (const nlohmann::json::exception& e) {
      throw Error(manifest.string() + " (boards[0])", std::string("a checker board needs inner_corners and square: ") + e.what());
    }
    dopt.board.Check(manifest.string() + " (boards[0])");
  } else {
    HOVS_REQUIRE(dopt.board.square > 0 && !truth_corners, manifest.string(),
                 "the manifest describes no checkerboard; give --board");
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0, noise > 0 ? noise : 1);
  for (const auto& fr : m["frames"])
    for (const auto& v : fr["views"]) {
      if (v["unit"] != uj["name"]) continue;
      HOVS_REQUIRE(!truth_corners || v.contains("ground_truth"), manifest.string(),
                   "--truth-corners needs ground truth, and frame ", JsonText(v, "image"), " has none");
      if (!truth_corners) {
        std::vector<Vec2d> gt;
        if (v.contains("ground_truth"))
          for (const scenes::CornerTruth& c : scenes::VisibleSidecarCorners(dir / v["ground_truth"]["sidecar"].get<std::string>()))
            gt.push_back(c.pixel);
        DetectInto(dir / v["image"].get<std::string>(), v["image"], dopt, v.contains("ground_truth") ? &gt : nullptr,
                   &in, &in.width, &in.height);
        continue;
      }
      calib::BoardObservation o;
      o.image = v["image"];
      for (const scenes::CornerTruth& c :
           scenes::VisibleSidecarCorners(dir / v["ground_truth"]["sidecar"].get<std::string>())) {
        o.board_points.emplace_back(c.board_xy.x(), c.board_xy.y(), 0.0);
        Vec2d px = c.pixel;
        if (noise > 0) px += Vec2d(N(rng), N(rng));
        o.pixels.push_back(px);
      }
      in.obs.push_back(o);
    }
  in.description = {{"dataset", manifest.string()}, {"unit", uj["name"]}};
  if (truth_corners) in.description.update({{"corners", "ground truth"}, {"corner_noise_px", noise}, {"seed", seed}});
  else in.description.update({{"corners", "hovs checkerboard detector"},
                              {"board", {dopt.board.cols, dopt.board.rows, dopt.board.square}}});
  return in;
}

nlohmann::json PolyJson(const calib::PolynomialCalibration& r, const std::vector<calib::BoardObservation>& obs) {
  const auto& m = r.model;
  nlohmann::json j = {{"model", "polynomial"},
                      {"cx", m.cx}, {"cy", m.cy}, {"c", m.c}, {"d", m.d}, {"e", m.e},
                      {"poly", m.poly}, {"inv_poly", m.inv_poly}, {"rho_range", {m.rho_min, m.rho_max}},
                      {"width", m.width}, {"height", m.height},
                      {"rms_px", r.rms}, {"mean_px", r.mean}, {"initial_rms_px", r.initial_rms},
                      {"converged", r.converged}, {"solver", r.solver_report}, {"stddev", r.stddev}};
  nlohmann::json per = nlohmann::json::array();
  for (size_t i = 0; i < obs.size(); ++i)
    per.push_back({{"image", obs[i].image}, {"corners", obs[i].pixels.size()}, {"rms_px", r.per_image_rms[i]},
                   {"mean_px", r.per_image_mean[i]}, {"above_5px", r.per_image_mean[i] > 5.0}});
  j["per_image"] = per;
  nlohmann::json outl = nlohmann::json::array();
  for (const auto& o : r.outliers)
    outl.push_back({{"image", o.image}, {"corner", o.corner}, {"residual_px", o.residual_px},
                    {"residual_after_px", o.residual_after_px}});
  j["outliers"] = outl;
  j["outlier_threshold_px"] = r.outlier_threshold_px;
  return j;
}

void ReprojectionFigure(const std::filesystem::path& image, const calib::BoardObservation& ob,
                        const std::vector<bool>& inlier, const PolynomialModel<double>& model,
                        const Rigid3d& cam_from_board, double rms, const std::filesystem::path& out) {
  const cv::Mat grey = GreyImage(image);
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
    cv::circle(crop, at(ob.pixels[k]), in ? 5 : 9, in ? cv::Scalar(0, 200, 0) : cv::Scalar(255, 0, 255), in ? 1 : 2, cv::LINE_AA);
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

// The article's Fig. 20 (OCamCalib's error plot): every corner's reprojection error (du, dv), one colour per
// image, rejected corners as crosses; beside it, where in the image the errors are (colour = error length).
void ErrorMapFigure(const std::vector<calib::BoardObservation>& obs, const calib::PolynomialCalibration& cal,
                    const std::filesystem::path& out) {
  const int S = 520, W = 2 * S + 20;
  cv::Mat fig(S + 40, W, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<std::vector<Vec2d>> res(obs.size());
  double extent = 0, worst_in = 0;
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t k = 0; k < obs[i].pixels.size(); ++k) {
      Vec2d uv(1e9, 1e9);
      cal.model.ImgFromCam(cal.cam_from_board[i] * obs[i].board_points[k], &uv);
      res[i].push_back(uv - obs[i].pixels[k]);
      const bool in = cal.inlier.empty() || cal.inlier[i][k];
      extent = std::max(extent, res[i].back().cwiseAbs().maxCoeff());
      if (in) worst_in = std::max(worst_in, res[i].back().norm());
    }
  extent = std::max(1e-3, std::min(extent, 4 * worst_in + 1e-3));
  // A round axis limit: 1, 2 or 5 times a power of ten.
  double lim = std::pow(10, std::floor(std::log10(extent)));
  for (double f : {1.0, 2.0, 5.0, 10.0})
    if (f * lim >= extent) { lim *= f; break; }
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
  for (int i = 0; i < hue.cols; ++i) hue.at<cv::Vec3b>(0, i) = cv::Vec3b(static_cast<uchar>(170 * i / std::max(1, hue.cols)), 230, 210);
  cv::cvtColor(hue, hue, cv::COLOR_HSV2BGR);
  for (size_t i = 0; i < obs.size(); ++i) {
    const cv::Vec3b c = hue.at<cv::Vec3b>(0, static_cast<int>(i));
    for (size_t k = 0; k < res[i].size(); ++k) {
      const Vec2d r = res[i][k].cwiseMax(Vec2d(-lim, -lim)).cwiseMin(Vec2d(lim, lim));
      if (cal.inlier.empty() || cal.inlier[i][k]) cv::circle(fig, at(r), 2, cv::Scalar(c[0], c[1], c[2]), cv::FILLED, cv::LINE_AA);
      else cv::drawMarker(fig, at(r), cv::Scalar(c[0], c[1], c[2]), cv::MARKER_TILTED_CROSS, 9, 2, cv::LINE_AA);
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
      cv::circle(fig, cv::Point2d(right.x + (obs[i].pixels[k].x() + 0.5) * sc, right.y + (obs[i].pixels[k].y() + 0.5) * sc), 3,
                 cv::Scalar(c[0], c[1], c[2]), cv::FILLED, cv::LINE_AA);
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

Runner SetupCalibrate(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string corners, size, dataset, unit, images, board, out = "results/calibration", loss = "none";
    bool truth_corners = false, physical = false, physical_intrinsics = false, physical_mirror = false, rim = true;
    std::string nominal;
    int subpix = 0;
    std::string corner_refinement = "edges";
    std::vector<int> degrees = {2, 3, 4, 5, 6};
    int degree = 4;
    double loss_scale = 1.0, noise = 0.0, outlier_sigmas = 5.0;
    uint64_t seed = 1;
    bool omnidir = false;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--corners", o->corners, "corner table: image,corner,board_x_mm,board_y_mm,u_px,v_px");
  sub->add_option("--size", o->size, "image size WxH (with --corners)");
  sub->add_option("--dataset", o->dataset, "dataset manifest (dataset.json): corners detected in its images");
  sub->add_option("--images", o->images, "folder of images (png, jpg, tif, exr): corners detected");
  sub->add_option("--board", o->board, "checkerboard COLSxROWSxSQUARE: inner corners and square (m), e.g. 7x6x0.03");
  sub->add_flag("--physical", o->physical,
                "also calibrate the physical model: mirror a, b and the camera's tilt and offset, exact projection");
  sub->add_option("--nominal", o->nominal,
                  "--physical: scene YAML with the unit's design (default: the manifest's unit, aligned)");
  sub->add_flag("--physical-intrinsics", o->physical_intrinsics,
                "--physical: also estimate the camera intrinsics (default: held at the nominal camera's, i.e. a camera "
                "calibrated without its mirror)");
  sub->add_flag("--physical-mirror", o->physical_mirror,
                "--physical: also estimate the mirror's a and b (default: held at the design; their common scale is "
                "weakly observable and drifts with corner noise)");
  sub->add_flag("!--no-rim", o->rim,
                "--physical: do not fit the rim of the mirror image (by default it is found in every image and fixes "
                "the camera's height and lateral place)");
  sub->add_flag("--truth-corners", o->truth_corners, "use a synthetic manifest's exact corners instead of detecting");
  sub->add_option("--corner-refinement", o->corner_refinement,
                  "edges: corners where the board lines measured along their length cross (default); subpix: "
                  "cv::cornerSubPix alone")
      ->capture_default_str();
  sub->add_option("--subpix-window", o->subpix, "cornerSubPix half window, px (0: 0.35 x the local square)")->check(Bounded(0, 100))
      ->capture_default_str();
  sub->add_option("--unit", o->unit, "unit name in the manifest (default: the first)");
  sub->add_option("--corner-noise", o->noise, "Gaussian noise added to ground-truth corners, px")->check(Bounded(0, 100))->capture_default_str();
  sub->add_option("--seed", o->seed, "seed of the corner noise")->check(Bounded(0, 9007199254740992.0))->capture_default_str();
  sub->add_option("--degree", o->degree, "polynomial degree of the reported model")->check(Bounded(2, 8))->capture_default_str();
  sub->add_option("--loss", o->loss, "none | huber | cauchy")->capture_default_str();
  sub->add_option("--loss-scale", o->loss_scale, "robust loss scale, px")->check(Bounded(0, 1000, true))->capture_default_str();
  sub->add_flag("--compare-omnidir", o->omnidir, "also run OpenCV omnidir on the same corners");
  sub->add_option("--outlier-sigmas", o->outlier_sigmas,
                  "reject corners above this many robust sigmas (at least 0.5 px) after the first solve; 0: keep all")->check(Bounded(0, 1000))
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    HOVS_REQUIRE(int(!o->corners.empty()) + int(!o->dataset.empty()) + int(!o->images.empty()) == 1,
                 "hovs calibrate", "give exactly one of --corners, --dataset and --images");
    HOVS_REQUIRE(std::isfinite(o->noise) && o->noise >= 0, "--corner-noise", "must be >= 0 px (got ", o->noise, ")");
    HOVS_REQUIRE(o->noise == 0 || o->truth_corners, "--corner-noise",
                 "adds noise to a synthetic manifest's exact corners: it needs --truth-corners");
    calib::CheckerboardDetectOptions detect;
    detect.subpix_half_window = o->subpix;
    detect.corner_refinement = o->corner_refinement;
    if (!o->board.empty()) detect.board = ParseBoard(o->board);
    else detect.board.square = 0;  // from the manifest
    Input in;
    if (!o->corners.empty()) {
      int w = 0, h = 0;
      char x = 0;
      int end = -1;
      HOVS_REQUIRE(std::sscanf(o->size.c_str(), "%d%c%d%n", &w, &x, &h, &end) == 3 && x == 'x' &&
                       end == static_cast<int>(o->size.size()) && w > 0 && h > 0 && w <= 65535 && h <= 65535,
                   "--size", "expected WxH of 1..65535 pixels each, e.g. 1024x768 (got '", o->size, "')");
      in.obs = calib::LoadCornerCsv(o->corners);
      in.width = w, in.height = h;
      in.description = {{"corners", o->corners}, {"size", {w, h}}};
      for (const auto& ob : in.obs)
        for (const auto& p : ob.pixels)
          HOVS_REQUIRE(p.x() >= -0.5 && p.y() >= -0.5 && p.x() <= w - 0.5 && p.y() <= h - 0.5, o->corners,
                       "corner (", p.x(), ", ", p.y(), ") of ", ob.image, " lies outside the ", w, "x", h, " image");
    } else if (!o->dataset.empty()) {
      in = FromDataset(o->dataset, o->unit, o->truth_corners, o->noise, o->seed, detect);
    } else {
      HOVS_REQUIRE(!o->board.empty(), "--images", "a folder of images needs --board");
      const auto files = ListImageFiles(o->images);
      for (const auto& f : files) DetectInto(f, f.filename().string(), detect, nullptr, &in, &in.width, &in.height);
      in.description = {{"images", o->images}, {"corners", "hovs checkerboard detector"},
                        {"board", {detect.board.cols, detect.board.rows, detect.board.square}}};
    }
    if (!in.detection.empty()) {
      std::string failed;
      for (const auto& d : in.detection)
        if (!d["found"].get<bool>()) failed += "; " + d["image"].get<std::string>() + ": " + d["status"].get<std::string>();
      HOVS_REQUIRE(in.obs.size() >= 3, o->dataset.empty() ? o->images : o->dataset, "only ", in.obs.size(),
                   " of ", in.detection.size(), " images have a usable board (at least 3 needed)", failed);
      if (!global->quiet && !failed.empty())
        std::fprintf(stderr, "hovs calibrate: no board in %s\n", failed.substr(2).c_str());
    }
    const std::string input_name = !o->corners.empty() ? o->corners : !o->dataset.empty() ? o->dataset : o->images;
    calib::PolynomialCalibrationOptions po;
    po.loss = o->loss, po.loss_scale = o->loss_scale, po.outlier_sigmas = o->outlier_sigmas;
    // Order selection table (the article's Tables 1-2), then the reported degree.
    nlohmann::json orders = nlohmann::json::array();
    std::optional<calib::PolynomialCalibration> chosen;
    for (int d : o->degrees) {
      po.degree = d;
      const auto r = OnInput(input_name, [&] { return calib::CalibratePolynomial(in.obs, in.width, in.height, po); });
      nlohmann::json row = {{"degree", d}, {"rms_px", r.rms}, {"mean_px", r.mean}, {"converged", r.converged},
                            {"per_image_mean_px", r.per_image_mean}};
      orders.push_back(row);
      if (d == o->degree) chosen = r;
    }
    if (!chosen) {
      po.degree = o->degree;
      chosen = OnInput(input_name, [&] { return calib::CalibratePolynomial(in.obs, in.width, in.height, po); });
    }
    // The unified and physical models and OpenCV omnidir see the corners the polynomial solve kept.
    const std::vector<calib::BoardObservation> inliers = calib::InlierObservations(in.obs, *chosen);
    const calib::UnifiedCalibration uni = OnInput(input_name, [&] {
      return calib::CalibrateUnified(inliers, in.width, in.height, *chosen, o->loss, o->loss_scale);
    });
    std::optional<calib::PhysicalCalibration> phys;
    std::optional<raytrace::CatadioptricUnit> phys_unit;
    size_t phys_rim_points = 0;
    if (o->physical) {
      raytrace::CatadioptricUnit nominal;
      if (!o->nominal.empty()) {
        auto cfg = scenes::LoadSceneConfig(o->nominal);
        if (!o->unit.empty()) scenes::SelectUnit(&cfg, o->unit);
        nominal = cfg.description.units[0];
      } else {
        HOVS_REQUIRE(in.truth.has_value(), "--physical", "give the unit's design with --nominal scene.yaml");
        nominal = *in.truth;  // the design of the manifest's unit, without its misalignment
      }
      nominal.rig.cam_from_mirror = scenes::MisalignedCamFromMirror(nominal.rig.mirror, Vec3d::Zero(), Vec3d::Zero(), 0);
      HOVS_REQUIRE(nominal.rig.camera.width == in.width && nominal.rig.camera.height == in.height, "--physical",
                   "the nominal camera is ", nominal.rig.camera.width, "x", nominal.rig.camera.height,
                   " but the images are ", in.width, "x", in.height);
      calib::PhysicalCalibrationOptions popt;
      popt.estimate_intrinsics = o->physical_intrinsics;
      popt.estimate_mirror = o->physical_mirror;
      if (o->rim && !in.paths.empty()) {   // a corner table has no images: corners only
        for (const auto& path : in.paths) {
          const cv::Mat g = GreyImage(path);
          calib::RimEdge edge;
          try {
            calib::LocateMirror(g.data, g.cols, g.rows, nominal.rig, {}, &edge, path.string());
          } catch (const Error& e) {
            if (!global->quiet) std::fprintf(stderr, "hovs calibrate: %s (the image is left out of the rim fit)\n", e.what());
            continue;
          }
          popt.rim_points.insert(popt.rim_points.end(), edge.points.begin(), edge.points.end());
        }
        HOVS_REQUIRE(popt.rim_points.size() >= 20, "--physical", "the rim of the mirror image was not found in the "
                     "images (--no-rim calibrates without it)");
      }
      phys = OnInput(input_name, [&] { return calib::CalibratePhysical(inliers, nominal.rig, *chosen, popt); });
      phys_rim_points = popt.rim_points.size();
      phys_unit = nominal;
      phys_unit->rig = phys->rig;
    }
    nlohmann::json j;
    j["tool"] = "hovs calibrate";
    j["versions"] = Versions();
    j["input"] = in.description;
    j["input"]["images"] = in.obs.size();
    if (!in.detection.empty()) j["detection"] = in.detection;
    std::string detection_summary;
    if (!in.detection.empty()) {
      int complete = 0, corners = 0, from_edges = 0;
      double ss = 0;
      int with_truth = 0;
      for (const auto& d : in.detection) {
        complete += d["complete"].get<bool>();
        if (!d["found"].get<bool>()) continue;
        corners += d["corners"].get<int>();
        from_edges += d["from_edges"].get<int>();
        if (d.contains("rms_to_truth_px"))
          ss += std::pow(d["rms_to_truth_px"].get<double>(), 2) * d["corners"].get<int>(), with_truth += d["corners"].get<int>();
      }
      detection_summary += "  detection: board in " + std::to_string(in.obs.size()) + " of " + std::to_string(in.detection.size()) +
                 " images (" + std::to_string(complete) + " complete), " + std::to_string(corners) + " corners (" +
                 std::to_string(from_edges) + " from the board's edges)";
      if (with_truth) {
        const double rms = std::sqrt(ss / with_truth);
        j["detection_rms_to_truth_px"] = rms;
        detection_summary += ", RMS " + F("%.4f", rms) + " px from the exact corners";
      }
      detection_summary += "\n";
    }
    j["polynomial"] = PolyJson(*chosen, in.obs);
    j["unified"] = {{"model", "unified_radtan"}, {"xi", uni.model.xi}, {"fx", uni.model.fx}, {"fy", uni.model.fy},
                    {"cx", uni.model.cx}, {"cy", uni.model.cy},
                    {"distortion", {uni.model.distortion.k1, uni.model.distortion.k2, uni.model.distortion.p1, uni.model.distortion.p2}},
                    {"rms_px", uni.rms}, {"mean_px", uni.mean}, {"converged", uni.converged}, {"solver", uni.solver_report},
                    {"stddev", uni.stddev}, {"opencv_yaml", "unified.yaml"}};
    j["order_selection"] = orders;
    if (phys) {
      const double deg = 180 / M_PI;
      j["physical"] = {{"model", "physical (hyperboloid + camera pose, exact projection)"},
                       {"a", phys->rig.mirror.a}, {"b", phys->rig.mirror.b},
                       {"tilt_deg", {phys->tilt.x() * deg, phys->tilt.y() * deg, phys->tilt.z() * deg}},
                       {"offset_m", {phys->offset.x(), phys->offset.y(), phys->offset.z()}},
                       {"intrinsics_estimated", o->physical_intrinsics}, {"mirror_estimated", o->physical_mirror},
                       {"rms_px", phys->rms}, {"converged", phys->converged}, {"solver", phys->solver_report},
                       {"rim_points", static_cast<int>(phys_rim_points)}, {"rim_rms_px", phys->rim_rms},
                       {"unit", scenes::UnitToJson(*phys_unit)}};
    }
    if (o->omnidir) {
      const auto cv = calib::RunOpenCvOmnidir(inliers, in.width, in.height);
      j["opencv_omnidir"] = cv.ok ? nlohmann::json{{"rms_px", cv.rms}, {"opencv_reported_rms", cv.opencv_rms},
                                                   {"images_used", cv.images_used}, {"xi", cv.xi}, {"fx", cv.fx},
                                                   {"fy", cv.fy}, {"cx", cv.cx}, {"cy", cv.cy}}
                                  : nlohmann::json{{"error", cv.error}};
    }
    if (in.truth) {
      // Mean angle between calibrated and true rays over the calibrated annulus (points at 2 m).
      const auto& rig = in.truth->rig;
      double sum = 0, worst = 0;
      int n = 0;
      std::vector<std::pair<Vec3d, Vec3d>> rays;
      const int step = std::max(4, in.width / 110);
      for (int v = 0; v < in.height; v += step)
        for (int u = 0; u < in.width; u += step) {
          const Vec2d uv(u, v);
          const double rho = chosen->model.SensorFromImg(uv).norm();
          if (!rig.SeesMirror(uv) || rho < chosen->model.rho_min || rho > chosen->model.rho_max) continue;
          // The true direction, from the viewpoint F1, of the point the pixel sees at 2 m: for a misaligned
          // (not single-viewpoint) rig the rays do not meet in F1, and a central model can only be right for
          // points at some distance.
          Vec3d M, d, b;
          if (!rig.RayFromImg(uv, &M, &d) || !chosen->model.CamFromImg(uv, &b)) continue;
          const Vec3d a = (M + 2.0 * d).normalized();
          const double ang = std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
          sum += ang, worst = std::max(worst, ang), ++n;
          rays.emplace_back(a.normalized(), b.normalized());
        }
      // The same after the best rotation of the model's frame onto the true one (Kabsch): a monocular
      // calibration fixes its frame only through the model's symmetry, so a small tilt of the whole frame is
      // nearly unobservable and harmless downstream (stereo calibration estimates the relative pose of the
      // calibrated frames). This is the ray accuracy that matters for depth.
      Mat3<double> H = Mat3<double>::Zero();
      for (const auto& [a, b] : rays) H += b * a.transpose();
      Eigen::JacobiSVD<Mat3<double>> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Mat3<double> D = Mat3<double>::Identity();
      D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() > 0 ? 1 : -1;
      const Mat3<double> R = svd.matrixV() * D * svd.matrixU().transpose();  // a ~ R b
      double sum_al = 0, worst_al = 0;
      for (const auto& [a, b] : rays) {
        const Vec3d rb = R * b;
        const double ang = std::atan2(a.cross(rb).norm(), a.dot(rb)) * 180 / M_PI;
        sum_al += ang, worst_al = std::max(worst_al, ang);
      }
      const double frame_rot = Eigen::AngleAxisd(R).angle() * 180 / M_PI;
      if (phys) {
        double ps = 0, pw = 0;
        int pn = 0;
        for (int v = 0; v < in.height; v += step)
          for (int u = 0; u < in.width; u += step) {
            const Vec2d uv(u, v);
            Vec3d M, d, Mp, dp;
            if (!rig.SeesMirror(uv) || !rig.RayFromImg(uv, &M, &d) || !phys->rig.RayFromImg(uv, &Mp, &dp)) continue;
            const Vec3d a = (M + 2.0 * d).normalized(), b = (Mp + 2.0 * dp).normalized();
            const double ang = std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
            ps += ang, pw = std::max(pw, ang), ++pn;
          }
        // Camera pose error: the rotation between the true and the calibrated cam_from_mirror (the tilt error),
        // and the distance between the camera centres.
        const Eigen::Quaterniond dq = rig.cam_from_mirror.rotation * phys->rig.cam_from_mirror.rotation.conjugate();
        const double tilt_err = 2 * std::asin(std::min(1.0, dq.vec().norm())) * 180 / M_PI;
        const double centre_err = (rig.CameraCentre() - phys->rig.CameraCentre()).norm();
        j["physical"]["ground_truth"] = {{"mean_ray_angle_deg", pn ? nlohmann::json(ps / pn) : nlohmann::json()},
                                         {"max_ray_angle_deg", pn ? nlohmann::json(pw) : nlohmann::json()},
                                         {"tilt_error_deg", tilt_err}, {"camera_centre_error_m", centre_err},
                                         {"pixels", pn}, {"true_a", rig.mirror.a}, {"true_b", rig.mirror.b},
                                         {"note", "over the whole mirror image, points at 2 m, mirror frame"}};
      }
      // No pixel to compare (the model's annulus misses the true mirror image): no figure, not a zero.
      const auto figure = [&](double v) { return n ? nlohmann::json(v) : nlohmann::json(); };
      j["ground_truth"] = {{"mean_ray_angle_deg", figure(sum / std::max(n, 1))}, {"max_ray_angle_deg", figure(worst)},
                           {"pixels", n}, {"mean_ray_angle_aligned_deg", figure(sum_al / std::max(n, 1))},
                           {"max_ray_angle_aligned_deg", figure(worst_al)},
                           {"frame_rotation_deg", frame_rot}, {"true_centre", {rig.camera.cx, rig.camera.cy}}};
    }
    StagedDirectory stage(o->out, "calibrate");
    WriteFileAtomic(stage.staging() / "calibration.json", j.dump(2) + "\n");
    WriteFileAtomic(stage.staging() / "calib_results.txt", calib::FormatOcamCalibResults(chosen->model));
    {
      calib::OmnidirFile of;
      of.model = uni.model, of.rms_px = uni.rms, of.stddev = uni.stddev;
      // The annulus the corners covered, measured around the unified model's centre.
      double rmin = HUGE_VAL, rmax = 0;
      for (const auto& ob : inliers)
        for (const auto& p : ob.pixels) {
          const double r = (p - Vec2d(uni.model.cx, uni.model.cy)).norm();
          rmin = std::min(rmin, r), rmax = std::max(rmax, r);
        }
      of.annulus_min = 0.9 * rmin, of.annulus_max = 1.05 * rmax;
      WriteFileAtomic(stage.staging() / "unified.yaml", calib::FormatOmnidirYaml(of));
    }
    std::string summary = "hovs calibrate: " + std::to_string(in.obs.size()) + " images\n" + detection_summary;
    summary += "  polynomial (degree " + std::to_string(chosen->model.Degree()) + "): RMS " + F("%.4f", chosen->rms) +
               " px, mean " + F("%.4f", chosen->mean) + " px (linear start " + F("%.3f", chosen->initial_rms) + " px)\n";
    if (!chosen->outliers.empty()) {
      summary += "  rejected " + std::to_string(chosen->outliers.size()) + " corners above " +
                 F("%.3f", chosen->outlier_threshold_px) + " px:";
      for (const auto& ol : chosen->outliers)
        summary += " " + ol.image + "#" + std::to_string(ol.corner) + " (" + F("%.2f", ol.residual_px) + ")";
      summary += "\n";
    }
    summary += "  unified + radtan:         RMS " + F("%.4f", uni.rms) + " px\n";
    if (j.contains("opencv_omnidir") && j["opencv_omnidir"].contains("rms_px"))
      summary += "  OpenCV omnidir (same corners): RMS " + F("%.4f", j["opencv_omnidir"]["rms_px"].get<double>()) + " px\n";
    if (j.contains("ground_truth") && j["ground_truth"]["pixels"].get<int>() == 0)
      summary += "  vs ground truth: no pixel of the model's annulus sees the true mirror; nothing to compare\n";
    else if (j.contains("ground_truth"))
      summary += "  vs ground truth: mean ray angle " + F("%.5f", j["ground_truth"]["mean_ray_angle_deg"].get<double>()) +
                 " deg; " + F("%.5f", j["ground_truth"]["mean_ray_angle_aligned_deg"].get<double>()) +
                 " deg after removing a frame rotation of " + F("%.4f", j["ground_truth"]["frame_rotation_deg"].get<double>()) +
                 " deg\n";
    if (phys) {
      summary += "  physical model: RMS " + F("%.4f", phys->rms) + " px, a " + F("%.5f", phys->rig.mirror.a) + " m, b " +
                 F("%.5f", phys->rig.mirror.b) + " m, tilt (" + F("%.3f", phys->tilt.x() * 180 / M_PI) + ", " +
                 F("%.3f", phys->tilt.y() * 180 / M_PI) + ") deg, offset (" + F("%.2f", phys->offset.x() * 1e3) + ", " +
                 F("%.2f", phys->offset.y() * 1e3) + ", " + F("%.2f", phys->offset.z() * 1e3) + ") mm" +
                 (phys_rim_points ? ", rim " + std::to_string(phys_rim_points) + " points (RMS " + F("%.3f", phys->rim_rms) + " px)" : "") + "\n";
      if (j.contains("physical") && j["physical"].contains("ground_truth") &&
          !j["physical"]["ground_truth"]["mean_ray_angle_deg"].is_null())
        summary += "  physical model vs ground truth: mean ray angle " +
                   F("%.5f", j["physical"]["ground_truth"]["mean_ray_angle_deg"].get<double>()) + " deg\n";
    }
    for (size_t i = 0; i < in.obs.size(); ++i)
      if (chosen->per_image_mean[i] > 5.0) summary += "  POOR: " + in.obs[i].image + " mean error above 5 px\n";
    WriteFileAtomic(stage.staging() / "summary.txt", summary);
    results::HtmlPage page("hovs calibration");
    page.Preformatted(summary);
    page.Heading("Per-image mean reprojection error by polynomial degree (px)");
    std::vector<std::string> header = {"image"};
    for (const auto& r : orders) header.push_back("N = " + std::to_string(r["degree"].get<int>()));
    std::vector<std::vector<std::string>> rows;
    for (size_t i = 0; i < in.obs.size(); ++i) {
      std::vector<std::string> row = {in.obs[i].image};
      for (const auto& r : orders) row.push_back(F("%.4f", r["per_image_mean_px"][i].get<double>()));
      rows.push_back(row);
    }
    std::vector<std::string> all = {"all (RMS)"};
    for (const auto& r : orders) all.push_back(F("%.4f", r["rms_px"].get<double>()));
    rows.push_back(all);
    page.Table(header, rows);
    if (!in.paths.empty()) {
      std::filesystem::create_directories(stage.staging() / "figures");
      page.Heading("Reprojection per image (polynomial model; residuals x20)");
      for (size_t i = 0; i < in.obs.size() && i < in.paths.size(); ++i) {
        const std::string fig = "figures/" + std::filesystem::path(in.obs[i].image).stem().string() + ".png";
        ReprojectionFigure(in.paths[i], in.obs[i], chosen->inlier[i], chosen->model, chosen->cam_from_board[i],
                           chosen->per_image_rms[i], stage.staging() / fig);
        page.Figure(fig, in.obs[i].image + ": RMS " + F("%.3f", chosen->per_image_rms[i]) + " px", 420);
      }
    }
    std::filesystem::create_directories(stage.staging() / "figures");
    ErrorMapFigure(in.obs, *chosen, stage.staging() / "figures/error_map.png");
    page.Heading("Reprojection error map (polynomial model; the article's Fig. 20)");
    page.Figure("figures/error_map.png", "left: (du, dv) of every corner, one colour per image, rejected corners as "
                "crosses; right: where in the image, colour = error length", 900);
    page.Heading("Result");
    page.Preformatted(j.dump(2));
    WriteFileAtomic(stage.staging() / "index.html", page.Render());
    stage.Commit();
    if (global->json) std::cout << j.dump(2) << "\n";
    else if (!global->quiet) std::cout << summary;
    return 0;
  };
}

}  // namespace hovs::apps
