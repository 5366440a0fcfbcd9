// OCamCalib's calib_results.txt: parsed, and a model that loads projects and back-projects.
#include "calib/ocam_io.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  const auto model = hovs::calib::ParseOcamCalibResults(input, "calib_results.txt");
  hovs::fuzz::UseModel(hovs::AnyModel::Polynomial(model, "calib_results.txt"));
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
