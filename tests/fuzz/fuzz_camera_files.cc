// Other tools' camera files: Kalibr's camchain and the MEI YAML (calib/camera_formats.h), parsed, and every
// model that loads projects and back-projects.
#include "calib/camera_formats.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  if (hovs::calib::LooksLikeMeiYaml(input)) {
    hovs::fuzz::UseModel(hovs::AnyModel::Unified(hovs::calib::ParseMeiYaml(input, "mei.yaml"), 0, 0, "mei.yaml"));
    return;
  }
  for (const auto& cam : hovs::calib::ParseKalibrCamchain(input, "camchain.yaml"))
    if (cam.camera_model == "omni")
      hovs::fuzz::UseModel(hovs::AnyModel::Unified(hovs::calib::UnifiedFromKalibr(cam, "cam"), 0, 0, "cam"));
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
