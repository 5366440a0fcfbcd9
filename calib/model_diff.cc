#include "calib/model_diff.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"
#include "results/plot.h"

namespace hovs::calib {

void ModelDiffOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(grid_step_px >= 0 && grid_step_px <= 10000, where, "the grid step must be 0 (automatic) to 10000 px");
}

ModelDiff DiffModels(const AnyModel& a, const AnyModel& b, const ModelDiffOptions& o) {
  o.Check("model diff options");
  HOVS_REQUIRE(a.width() == b.width() && a.height() == b.height(), "model diff", "the models are for images of ",
               a.width(), "x", a.height(), " and ", b.width(), "x", b.height(), ": not one camera");
  ModelDiff d;
  d.width = a.width(), d.height = a.height();
  d.step_px = o.grid_step_px > 0 ? o.grid_step_px : std::max(1, static_cast<int>(std::lround(d.width / 120.0)));
  d.nx = (d.width - 1) / d.step_px + 1, d.ny = (d.height - 1) / d.step_px + 1;
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

void WriteModelDiffFigures(const ModelDiff& d, const std::string& title, const std::filesystem::path& px_png,
                           const std::filesystem::path& deg_png) {
  const auto figure = [&](const std::vector<double>& values, const std::string& what, const SampleSummary& s,
                          const char* format, const std::filesystem::path& path) {
    results::HeatMapFigure f;
    f.title = title + ": " + what + " (median " + FormatNumber(format, s.median) + ", 95 % " +
              FormatNumber(format, s.p95) + ")";
    f.x_label = "u (px)", f.y_label = "-v (px)", f.value_label = what;
    f.nx = d.nx, f.ny = d.ny;
    f.x0 = 0, f.x1 = (d.nx - 1) * d.step_px, f.y0 = -(d.ny - 1) * d.step_px, f.y1 = 0;
    f.width = 900, f.height = std::max(400, 900 * d.height / std::max(1, d.width));
    f.values.resize(values.size()), f.shade.resize(values.size());
    for (int j = 0; j < d.ny; ++j)  // figure row j is image row ny - 1 - j (image up is figure up)
      for (int i = 0; i < d.nx; ++i) {
        const double v = values[(d.ny - 1 - j) * d.nx + i];
        f.values[j * d.nx + i] = std::isfinite(v) ? v : 0;
        f.shade[j * d.nx + i] = !std::isfinite(v);
      }
    f.shade_label = "pale: outside either model's domain";
    f.contour_levels = {s.median, s.p95};
    f.contour_format = format;
    results::WritePng(f, path);
  };
  figure(d.px, "difference, px", d.px_stats, "%.3f", px_png);
  figure(d.deg, "difference, degrees", d.deg_stats, "%.4f", deg_png);
}

}  // namespace hovs::calib
