// Reference images of virtual views: each perspective view rendered with a pinhole camera at a unit's viewpoint
// (the scene without the units' hardware), to compare unwrapped views with (PSNR).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/virtual_view.h"
#include "scenes/scene_config.h"

namespace hovs::scenes {

// One entry per view: RGB8 of the view's size for a perspective view, nothing for a panorama. unit: the unit's
// name (empty: the first); `where` names the scene in errors.
std::vector<std::optional<std::vector<uint8_t>>> RenderTruthViews(const SceneConfig& cfg, const std::string& unit,
                                                                  const std::vector<VirtualView<double>>& views,
                                                                  int samples, const std::string& where);

// A panorama's reference image (RGB8 of the view's size): a ring of eight pinhole renders at the unit's viewpoint
// (the scene without the units' hardware), 60 degrees wide and at the panorama's angular resolution, resampled
// bilinearly into its pixels. `view` is a cylindrical or longitude-latitude panorama in the unit's mirror frame
// spanning at most 120 degrees of elevation. Throws naming `where` otherwise.
std::vector<uint8_t> RenderTruthPanorama(const SceneConfig& cfg, const std::string& unit,
                                         const VirtualView<double>& view, int samples, const std::string& where);

}  // namespace hovs::scenes
