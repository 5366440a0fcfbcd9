// hovs unwrap with a rig layout (views of several units, e.g. --layout binocular) or a rig mapping file: each
// frame's images of every unit expanded together into the layout's views.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "unwrap/remap.h"

namespace hovs::apps {

struct RigUnwrapOptions {
  std::string model, layout, map, save_map, input, out, interp, format;
  double scene_distance = 10;
  int tile = 0;
  bool fixed_elevation = false;
};

// An input frame as 8-bit pixels in the format `format` names (auto: grey or RGB as stored; bayer_rggb: a mosaic),
// checked against the size its model maps (width x height). Throws naming the image.
std::vector<uint8_t> LoadFrameBytes(const std::filesystem::path& image, const std::string& format, int width,
                                    int height, unwrap::PixelFormat* fmt);

// True when the layout (a preset or a YAML file) names units, or the --map file is a rig mapping.
bool IsRigUnwrap(const std::string& layout, const std::string& map);

// Inputs: a dataset manifest (each frame's view of every unit) or a folder with one subfolder per unit (images
// paired by file name). A frame without every unit's image is listed as unpaired and not expanded.
int RunRigUnwrap(const RigUnwrapOptions& o, const GlobalOptions& global);

}  // namespace hovs::apps
