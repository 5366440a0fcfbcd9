#include "calib/model_diff.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/format.h"
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace hovs::calib {

void ModelDiffOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(grid_step_px >= 0 && grid_step_px <= 10000, where, "the grid step must be 0 (automatic) to 10000 px");
}

ImageGrid ImageGrid::Over(int width, int height, int step_px) {
  ImageGrid g;
  g.width = width, g.height = height;
  g.step_px = step_px > 0 ? step_px : std::max(1, static_cast<int>(std::lround(width / 120.0)));
  g.nx = (width - 1) / g.step_px + 1, g.ny = (height - 1) / g.step_px + 1;
  return g;
}

ModelDiff DiffModels(const AnyModel& a, const AnyModel& b, const ModelDiffOptions& o) {
  o.Check("model diff options");
  HOVS_REQUIRE(a.width() == b.width() && a.height() == b.height(), "model diff", "the models are for images of ",
               a.width(), "x", a.height(), " and ", b.width(), "x", b.height(), ": not one camera");
  ModelDiff d;
  static_cast<ImageGrid&>(d) = ImageGrid::Over(a.width(), a.height(), o.grid_step_px);
  std::vector<Vec3d> ba(d.nx * d.ny), bb(d.nx * d.ny);
  std::vector<char> common(d.nx * d.ny, 0);
  std::vector<std::pair<Vec3d, Vec3d>> pairs;
  for (int j = 0; j < d.ny; ++j)
    for (int i = 0; i < d.nx; ++i) {
      const int k = j * d.nx + i;
      const Vec2d uv(i * d.step_px, j * d.step_px);
      common[k] = a.MirrorFromImg(uv, &ba[k]) && b.MirrorFromImg(uv, &bb[k]);
      if (common[k]) pairs.emplace_back(bb[k], ba[k]);
    }
  d.common_pixels = pairs.size();
  HOVS_REQUIRE(d.common_pixels >= 100, "model diff", "the two models share only ", d.common_pixels,
               " grid pixels of their valid domains: nothing to compare");
  if (o.fit_rotation) d.b_from_a = BestRotation(pairs);
  d.rotation_deg = Eigen::AngleAxisd(d.b_from_a).angle() * 180 / M_PI;
  d.px.assign(d.nx * d.ny, NAN), d.deg.assign(d.nx * d.ny, NAN);
  std::vector<double> px, deg;
  for (int j = 0; j < d.ny; ++j)
    for (int i = 0; i < d.nx; ++i) {
      const int k = j * d.nx + i;
      if (!common[k]) continue;
      const Vec3d turned = d.b_from_a * ba[k];
      Vec2d uv;
      if (!b.ImgFromMirror(turned, &uv)) continue;
      d.px[k] = (uv - Vec2d(i * d.step_px, j * d.step_px)).norm();
      d.deg[k] = AngleBetweenDeg(turned, bb[k]);
      px.push_back(d.px[k]), deg.push_back(d.deg[k]);
    }
  d.px_stats = Summarise(px), d.deg_stats = Summarise(deg);
  return d;
}

ModelDiff RmsOfDiffs(const std::vector<ModelDiff>& diffs) {
  HOVS_REQUIRE(!diffs.empty(), "model diff", "no diffs to combine");
  ModelDiff r = diffs[0];
  for (const auto& d : diffs)
    HOVS_REQUIRE(d.nx == r.nx && d.ny == r.ny && d.step_px == r.step_px, "model diff", "the grids differ");
  std::vector<double> px, deg;
  double rot = 0;
  for (const auto& d : diffs) rot += d.rotation_deg * d.rotation_deg;
  r.rotation_deg = std::sqrt(rot / diffs.size());
  r.b_from_a = Mat3<double>::Identity();
  r.common_pixels = 0;
  for (size_t k = 0; k < r.px.size(); ++k) {
    double sp = 0, sd = 0;
    bool all = true;
    for (const auto& d : diffs) {
      all = all && std::isfinite(d.px[k]);
      if (all) sp += d.px[k] * d.px[k], sd += d.deg[k] * d.deg[k];
    }
    r.px[k] = all ? std::sqrt(sp / diffs.size()) : NAN;
    r.deg[k] = all ? std::sqrt(sd / diffs.size()) : NAN;
    if (all) px.push_back(r.px[k]), deg.push_back(r.deg[k]), ++r.common_pixels;
  }
  r.px_stats = Summarise(px), r.deg_stats = Summarise(deg);
  return r;
}

nlohmann::json ModelDiffJson(const ModelDiff& d) {
  const auto stats = [](const SampleSummary& s) {
    return nlohmann::json{{"mean", s.mean}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
  };
  return {{"grid_step_px", d.step_px},
          {"common_pixels", d.common_pixels},
          {"rotation_deg", d.rotation_deg},
          {"px", stats(d.px_stats)},
          {"deg", stats(d.deg_stats)}};
}

// The image at up to 800 px wide, each grid cell coloured by its value; title above, colour bar below. OpenCV
// only: no display.
void WriteGridMap(const ImageGrid& d, const std::vector<double>& values, const std::string& title,
                  const SampleSummary& s, const char* format, const std::string& grey_note,
                  const std::filesystem::path& path) {
  std::vector<double> finite;
  for (double v : values)
    if (std::isfinite(v)) finite.push_back(v);
  std::sort(finite.begin(), finite.end());
  double top = finite.empty() ? 1 : finite[std::min(finite.size() - 1, finite.size() * 99 / 100)];
  if (!(top > 0)) top = 1;
  const double scale = std::min(1.0, 800.0 / d.width);
  const int w = std::max(1, static_cast<int>(d.width * scale)), h = std::max(1, static_cast<int>(d.height * scale));
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int k = 0; k < 256; ++k) ramp.at<uchar>(0, k) = static_cast<uchar>(k);
  cv::applyColorMap(ramp, ramp, cv::COLORMAP_TURBO);
  const auto colour = [&](double v) {
    const int k = std::clamp(static_cast<int>(255 * v / top), 0, 255);
    return ramp.at<cv::Vec3b>(0, k);
  };
  cv::Mat fig(h + 110, std::max(w, 420), CV_8UC3, cv::Scalar(255, 255, 255));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = std::clamp(static_cast<int>(std::lround(x / scale / d.step_px)), 0, d.nx - 1);
      const int j = std::clamp(static_cast<int>(std::lround(y / scale / d.step_px)), 0, d.ny - 1);
      const double v = values[j * d.nx + i];
      fig.at<cv::Vec3b>(30 + y, x) = std::isfinite(v) ? colour(v) : cv::Vec3b(225, 225, 225);
    }
  const auto put = [&](const std::string& t, int x, int y) {
    cv::putText(fig, t, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  };
  put(title + ": median " + FormatNumber(format, s.median) + ", 95 % " + FormatNumber(format, s.p95) + ", max " +
          FormatNumber(format, s.max),
      4, 20);
  const int bar_y = 30 + h + 15, bar_w = std::min(fig.cols - 20, 400);
  for (int x = 0; x < bar_w; ++x)
    cv::line(fig, cv::Point(10 + x, bar_y), cv::Point(10 + x, bar_y + 14), cv::Scalar(colour(top * x / bar_w)));
  put("0", 8, bar_y + 32);
  put(FormatNumber(format, top), 10 + bar_w - 40, bar_y + 32);
  put("grey: " + grey_note, 10, bar_y + 50);
  HOVS_REQUIRE(cv::imwrite(path.string(), fig), path.string(), "cannot write the figure");
}

void WriteModelDiffFigures(const ModelDiff& d, const std::string& title, const std::filesystem::path& px_png,
                           const std::filesystem::path& deg_png) {
  const std::string note = "outside either model's domain";
  WriteGridMap(d, d.px, title + ", px", d.px_stats, "%.3f", note, px_png);
  WriteGridMap(d, d.deg, title + ", degrees", d.deg_stats, "%.4f", note, deg_png);
}

}  // namespace hovs::calib
