#include "scenes/truth_views.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "raytrace/render.h"

namespace hovs::scenes {

std::vector<std::optional<std::vector<uint8_t>>> RenderTruthViews(const SceneConfig& cfg, const std::string& unit,
                                                                  const std::vector<VirtualView<double>>& views,
                                                                  int samples, const std::string& where) {
  const auto& units = cfg.description.units;
  size_t ui = 0;
  if (!unit.empty()) {
    ui = units.size();
    for (size_t k = 0; k < units.size(); ++k)
      if (units[k].name == unit) ui = k;
    HOVS_REQUIRE(ui < units.size(), "--unit " + unit, "no such unit in ", where);
  }
  raytrace::SceneDescription bare = cfg.description;
  bare.units.clear();
  const raytrace::RayScene scene(bare);
  raytrace::RenderOptions ro = cfg.render;
  ro.samples = samples;
  ro.ground_truth = false;
  ro.Check("--truth-samples");
  std::vector<std::optional<std::vector<uint8_t>>> truth(views.size());
  for (size_t v = 0; v < views.size(); ++v) {
    const auto& view = views[v];
    if (view.projection != ViewProjection::kPerspective) continue;
    const Rigid3d world_from_view = units[ui].world_from_mirror * Rigid3d(view.mirror_from_view, Vec3d::Zero());
    const auto fr = raytrace::Render(scene, raytrace::ViewCamera::Pinhole(view.camera, world_from_view), ro);
    std::vector<uint8_t> bytes(fr.rgb.size());
    for (size_t k = 0; k < bytes.size(); ++k) bytes[k] = uint8_t(std::lround(std::clamp(fr.rgb[k], 0.f, 1.f) * 255));
    truth[v] = std::move(bytes);
  }
  return truth;
}

std::vector<uint8_t> RenderTruthPanorama(const SceneConfig& cfg, const std::string& unit,
                                         const VirtualView<double>& view, int samples, const std::string& where) {
  HOVS_REQUIRE(view.projection == ViewProjection::kCylindrical || view.projection == ViewProjection::kLongLat, where,
               "a truth panorama needs a cylindrical or longitude-latitude view");
  const double e_lo = view.elevation_min, e_hi = view.elevation_max;
  HOVS_REQUIRE(e_hi - e_lo <= 120 * M_PI / 180, where, "a truth panorama spans at most 120 degrees of elevation");
  // The ring: eight views 45 degrees apart around the panorama's pole, each 60 degrees wide, tall enough for the
  // elevation range with 8 degrees to spare, at the panorama's pixels per radian along its equator.
  const double px_per_rad = view.width / view.azimuth_span;
  const double hfov = 60 * M_PI / 180, vfov = (e_hi - e_lo) + 16 * M_PI / 180;
  const int w = static_cast<int>(std::ceil(2 * px_per_rad * std::tan(hfov / 2)));
  const int h = static_cast<int>(std::ceil(2 * px_per_rad * std::tan(vfov / 2)));
  HOVS_REQUIRE(vfov < M_PI * 0.95, where, "the panorama's elevation range is too tall for a pinhole ring");
  std::vector<VirtualView<double>> ring;
  for (int k = 0; k < 8; ++k) {
    VirtualView<double> p = VirtualView<double>::Perspective(w, h, hfov, k * M_PI / 4, 0.5 * (e_lo + e_hi), 0.0);
    p.camera.fy = p.camera.fx;  // square pixels (Perspective does so too; kept explicit)
    p.mirror_from_view = view.mirror_from_view * p.mirror_from_view;
    ring.push_back(p);
  }
  const auto renders = RenderTruthViews(cfg, unit, ring, samples, where);
  std::vector<uint8_t> out(size_t(view.width) * view.height * 3, 0);
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      Vec3d b;
      if (!view.MirrorFromImg(Vec2d(x, y), &b)) continue;
      int best = 0;
      double best_dot = -2;
      for (int k = 0; k < 8; ++k) {
        const double d = b.dot(ring[k].mirror_from_view * Vec3d(0, 0, 1));
        if (d > best_dot) best_dot = d, best = k;
      }
      Vec2d uv;
      if (!ring[best].ImgFromMirror(b, &uv)) continue;
      const auto& im = *renders[best];
      const double fx = std::clamp(uv.x(), 0.0, w - 1.0), fy = std::clamp(uv.y(), 0.0, h - 1.0);
      const int x0 = std::min(static_cast<int>(fx), w - 2), y0 = std::min(static_cast<int>(fy), h - 2);
      const double ax = fx - x0, ay = fy - y0;
      for (int c = 0; c < 3; ++c) {
        const auto at = [&](int xx, int yy) { return double(im[(size_t(yy) * w + xx) * 3 + c]); };
        const double v = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
                         ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1));
        out[(size_t(y) * view.width + x) * 3 + c] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
      }
    }
  return out;
}

}  // namespace hovs::scenes
