// Learning-ready export of a rendered dataset for 360-degree depth networks (the layout OmniMVS-style pipelines
// read): per frame and unit, an equirectangular (longitude-latitude) RGB image, the ground-truth range and a
// validity mask, and every unit's pose per frame.
//
// Folder (written by ExportEquirect):
//   <unit>/rgb/<frame>.png     8-bit RGB, W x W/2, the unit's mirror frame (z up the mirror axis):
//                              column u: azimuth = 180 - 360 (u + 0.5) / W degrees (from +x towards +y; it
//                                        decreases to the right, so that the image reads as seen from inside)
//                              row v:    elevation = 90 - 180 (v + 0.5) / H degrees
//   <unit>/range/<frame>.exr   float32, one channel named Y (what cv2.imread reads of a one-channel EXR): range (m)
//                              from the viewpoint F1 along the pixel's ray; 0 where the mask is 0 and for the sky
//   <unit>/mask/<frame>.png    255 where the pixel sees the scene through the mirror, else 0
//   poses.json                 per frame and unit: world_from_mirror {q: [w, x, y, z], t}, the layout above, the
//                              dataset and its versions
// RGB is the fast remap of the rendered image (bilinear); range and mask take the nearest source pixel's ground
// truth (interpolating range across an edge would invent surfaces). A pixel's 3-D point is range x bearing with
// bearing = (cos el cos az, cos el sin az, sin el); world point = world_from_mirror * it.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hovs::depth {

struct EquirectOptions {
  int width = 1024;       // the height is width / 2
  bool progress = false;  // a progress line on stderr (the maps' build, then each view)
  void Check(const std::string& where) const;
};

struct EquirectExport {
  int frames = 0, units = 0;
  double valid_fraction = 0;  // of all exported pixels, the mask's share
};

// Writes the folder into `folder` (an existing, empty staging folder). Throws hovs::Error naming the manifest
// when it is not a rendered dataset (no ground truth), and "--width" when the maps and one view's buffers would
// not fit in the memory left (EquirectMemoryBytes), before anything is built.
// The memory an export of `units` units at `width` takes at its peak: each unit's per-pixel map and one view's
// buffers (RGB, range, mask, the remapped view).
size_t EquirectMemoryBytes(int width, size_t units);

EquirectExport ExportEquirect(const std::filesystem::path& manifest, const EquirectOptions& options,
                              const std::filesystem::path& folder, const nlohmann::json& versions);

}  // namespace hovs::depth
