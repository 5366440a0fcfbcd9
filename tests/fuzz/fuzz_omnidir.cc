// OpenCV omnidir YAML (the unified model): parsed, and a model that loads projects and back-projects.
#include "calib/omnidir_io.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  const auto f = hovs::calib::ParseOmnidirYaml(input, "unified.yaml");
  hovs::fuzz::UseModel(hovs::AnyModel::Unified(f.model, f.annulus_min, f.annulus_max, "unified.yaml"));
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
