// OpenCV omnidir YAML or XML (the unified model; XML through cv::FileStorage): parsed, and a model that loads
// projects and back-projects.
#include "calib/omnidir_io.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  const auto f = hovs::calib::LooksLikeOmnidirXml(input) ? hovs::calib::ParseOmnidirXml(input, "unified.xml")
                                                         : hovs::calib::ParseOmnidirYaml(input, "unified.yaml");
  const auto model = hovs::calib::WithImageSize(f, 640, 480, "unified");
  hovs::fuzz::UseModel(hovs::AnyModel::Unified(model, f.annulus_min, f.annulus_max, "unified"));
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
