#include "apps/commands.h"

namespace hovs::apps {

const std::vector<Command>& Commands() {
  static const std::vector<Command> table = {
      {"design", "Mirror design study: sweep (a, b[, d]), constrained optima, report with figures", SetupDesign},
      {"render", "Render a scene through its catadioptric units, with ground truth (EXR + JSON)", SetupRender},
      {"dataset", "Render a dataset (a monocular calibration set) with ground truth and a manifest", SetupDataset},
      {"calibrate", "Monocular calibration (polynomial and unified models) from a corner table or a dataset", SetupCalibrate},
      {"unwrap", "Virtual perspective views and panoramas from catadioptric images (any model), mapping files", SetupUnwrap},
      {"stereo-calibrate", "Relative pose of two units from ArUco board pairs (detection in unwrapped views, joint solve)", SetupStereoCalibrate},
      {"depth", "Dense and sparse binocular depth of a two-unit dataset (rectification, SGBM, point clouds)", SetupDepth},
      {"version", "Print the versions of hovs and its libraries", SetupVersion},
  };
  return table;
}

}  // namespace hovs::apps
