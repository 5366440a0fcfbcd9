// The interactive control panel of hovs unwrap (the article's Algorithm 4 DISPLAY/ADJUST): one window per
// layout, a view selector and sliders for yaw, pitch, roll and field of view (perspective) or elevation range
// (panoramas). Each change rebuilds that view's mapping and remaps the frame. Keys: s saves the adjusted layout
// as YAML, q or Esc quits. Needs a display; never used by tests.
#pragma once

#include <filesystem>
#include <string>

#include "core/any_model.h"
#include "unwrap/layout.h"
#include "unwrap/remap.h"

namespace hovs::apps {

// Returns when the user quits. Throws hovs::Error when no display is available.
void RunUnwrapViewer(const AnyModel& model, unwrap::Layout layout, const unwrap::ImageView& frame,
                     const std::filesystem::path& layout_out);

// The layout as YAML (the format LoadLayout reads).
std::string LayoutYaml(const unwrap::Layout& layout);

}  // namespace hovs::apps
