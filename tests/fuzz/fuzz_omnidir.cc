// OpenCV omnidir YAML (the unified model): parsed, and a model that loads projects and back-projects.
#include "calib/omnidir_io.h"
#include "core/any_model.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  const auto f = hovs::calib::ParseOmnidirYaml(input, "unified.yaml");
  const hovs::AnyModel m = hovs::AnyModel::Unified(f.model, f.annulus_min, f.annulus_max, "unified.yaml");
  hovs::Vec3d b;
  hovs::Vec2d uv;
  for (int k = 0; k < 16; ++k)
    if (m.MirrorFromImg(hovs::Vec2d(k * m.width() / 16.0, k * m.height() / 16.0), &b)) m.ImgFromMirror(b, &uv);
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
