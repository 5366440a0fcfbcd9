// The reference calibration scene at a quarter of the resolution (same optics and field of view, 16 x fewer
// pixels) and one sample per pixel: quick datasets for tests.
#pragma once

#include <string>

#include "scenes/scene_config.h"

namespace hovs::test {

inline scenes::SceneConfig SmallCalibrationScene() {
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
  cfg.description.units[0].rig.camera = PinholeCamera<double>::FromPhysical(0.016, 4 * 4.54e-6, 688, 550);
  cfg.render.samples = 1;
  return cfg;
}

}  // namespace hovs::test
