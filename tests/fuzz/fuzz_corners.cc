// Corner tables (image,corner,board_x_mm,board_y_mm,u_px,v_px).
#include "calib/polynomial_calibration.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) { hovs::calib::ParseCornerCsv(input, "corners.csv"); }

}  // namespace

HOVS_FUZZ_TARGET(Run)
