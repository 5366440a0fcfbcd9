#include "calib/model_io.h"

#include "calib/ocam_io.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"

namespace hovs::calib {

PolynomialModel<double> PolynomialFromJson(const nlohmann::json& p, const std::string& where) {
  HOVS_REQUIRE(p.is_object(), where, "expected the polynomial model's object");
  PolynomialModel<double> m;
  m.width = static_cast<int>(JsonInteger(p, "width", 1, 65535, where));
  m.height = static_cast<int>(JsonInteger(p, "height", 1, 65535, where));
  m.cx = JsonNumber(p, "cx", where), m.cy = JsonNumber(p, "cy", where);
  m.c = JsonNumber(p, "c", where), m.d = JsonNumber(p, "d", where), m.e = JsonNumber(p, "e", where);
  m.poly = JsonNumbers(p, "poly", 2, 21, where);
  m.inv_poly = JsonNumbers(p, "inv_poly", 0, 64, where);
  if (p.contains("inverse")) {
    const auto& inv = p["inverse"];
    m.inv_cheb = JsonNumbers(inv, "chebyshev", 1, 64, where + ".inverse");
    const std::vector<double> range = JsonNumbers(inv, "theta_range", 2, 2, where + ".inverse");
    m.inv_theta_lo = range[0], m.inv_theta_hi = range[1];
    m.inv_error_px = JsonNumber(inv, "max_error_px", where + ".inverse");
  }
  const std::vector<double> rho = JsonNumbers(p, "rho_range", 2, 2, where);
  m.rho_min = rho[0], m.rho_max = rho[1];
  if (p.contains("decentering")) {
    const std::vector<double> pp = JsonNumbers(p, "decentering", 2, 2, where);
    m.p1 = pp[0], m.p2 = pp[1];
  }
  m.Check(where);
  return m;
}

PolynomialModel<double> LoadPolynomialModelFile(const std::filesystem::path& path) {
  if (path.extension() == ".txt") return LoadOcamCalibResults(path);
  const auto j = ReadJsonFile(path);
  HOVS_REQUIRE(j.is_object() && j.contains("polynomial"), path.string(),
               "not calib_results.txt or a hovs calibration.json (no 'polynomial' model)");
  return PolynomialFromJson(j["polynomial"], path.string() + " (polynomial)");
}

}  // namespace hovs::calib
