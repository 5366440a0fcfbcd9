// hovs.calibrate: the monocular calibration of `hovs calibrate` (calib/mono_calibration.h) from corners given as
// arrays: the polynomial and unified models with their record (calibration.json's content).
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "calib/mono_calibration.h"
#include "python/arrays.h"
#include "python/bindings.h"

namespace hovs::python {

namespace {

calib::BoardObservation Observation(const py::handle& item, size_t index) {
  const std::string where = "observations[" + std::to_string(index) + "]";
  if (!py::isinstance<py::dict>(item)) throw py::type_error(where + ": expected a dict with board_xy and pixels");
  const py::dict d = py::reinterpret_borrow<py::dict>(item);
  HOVS_REQUIRE(d.contains("board_xy") && d.contains("pixels"), where, "needs board_xy (K, 2) and pixels (K, 2)");
  const Rows board = AsRows(d["board_xy"], 2, where + ".board_xy");
  const Rows pixels = AsRows(d["pixels"], 2, where + ".pixels");
  HOVS_REQUIRE(board.n == pixels.n && !board.single && board.n >= 4, where, "board_xy and pixels need the same ",
               "number of rows, at least 4 (got ", board.n, " and ", pixels.n, ")");
  calib::BoardObservation o;
  o.image = d.contains("image") ? py::str(d["image"]).cast<std::string>() : "image" + std::to_string(index);
  for (py::ssize_t k = 0; k < board.n; ++k) {
    const Vec3d b(board.data()[2 * k], board.data()[2 * k + 1], 0);
    const Vec2d p(pixels.data()[2 * k], pixels.data()[2 * k + 1]);
    HOVS_REQUIRE(b.allFinite() && p.allFinite(), where, "row ", k, " is not finite");
    o.board_points.push_back(b), o.pixels.push_back(p);
  }
  return o;
}

py::tuple Calibrate(const py::list& observations, int width, int height, int degree, const std::string& loss,
                    bool uncertainty) {
  HOVS_REQUIRE(width > 0 && height > 0 && width <= 65535 && height <= 65535, "width/height",
               "the image size must be 1..65535 pixels a side");
  HOVS_REQUIRE(degree >= 2 && degree <= 8, "degree", "must be 2..8 (got ", degree, ")");
  calib::CalibrationInput in;
  in.width = width, in.height = height;
  for (size_t i = 0; i < observations.size(); ++i) in.observations.push_back(Observation(observations[i], i));
  in.description = {{"source", "hovs.calibrate (Python)"}, {"images", in.observations.size()}};
  calib::MonoCalibrationOptions options;
  options.polynomial.degree = degree, options.polynomial.loss = loss;
  options.uncertainty = uncertainty;
  const auto [result, record] = [&] {
    py::gil_scoped_release release;
    calib::MonoCalibration r = calib::CalibrateMono(in, options);
    nlohmann::json j = calib::MonoCalibrationJson(in, options, r);
    return std::make_pair(std::move(r), std::move(j));
  }();
  double a0 = 0, a1 = 0;
  calib::CornerAnnulus(result, &a0, &a1);
  Camera poly{AnyModel::Polynomial(result.polynomial.model, "hovs.calibrate (polynomial)"),
              "hovs.calibrate (polynomial)"};
  Camera unified{AnyModel::Unified(result.unified.model, a0, a1, "hovs.calibrate (unified)"),
                 "hovs.calibrate (unified)"};
  const py::object json = py::module_::import("json").attr("loads")(record.dump());
  return py::make_tuple(json, poly, unified);
}

}  // namespace

void BindCalibration(py::module_& m) {
  m.def("calibrate", &Calibrate, py::arg("observations"), py::arg("width"), py::arg("height"), py::arg("degree") = 4,
        py::arg("loss") = "none", py::arg("uncertainty") = false,
        "The monocular calibration of `hovs calibrate` from corners: observations is a list of dicts with board_xy "
        "(K, 2) metres on the board, pixels (K, 2) and optionally image (a name). Returns (record, polynomial "
        "Camera, unified Camera); record is calibration.json's content (models, errors, rejected corners, board "
        "poses). uncertainty: also the projection-uncertainty maps (slower).");
}

}  // namespace hovs::python
