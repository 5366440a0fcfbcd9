// OCamCalib's calib_results.txt: parsed, and a model that loads projects and back-projects.
#include "calib/ocam_io.h"
#include "core/any_model.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  const auto model = hovs::calib::ParseOcamCalibResults(input, "calib_results.txt");
  const hovs::AnyModel m = hovs::AnyModel::Polynomial(model, "calib_results.txt");
  hovs::Vec3d b;
  hovs::Vec2d uv;
  for (int k = 0; k < 16; ++k)
    if (m.MirrorFromImg(hovs::Vec2d(k * m.width() / 16.0, k * m.height() / 16.0), &b)) m.ImgFromMirror(b, &uv);
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
