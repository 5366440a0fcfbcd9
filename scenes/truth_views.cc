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

}  // namespace hovs::scenes
