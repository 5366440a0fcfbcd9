// Calibrated model files, read once here for every layer: the polynomial (OCam) model of a hovs calibration.json
// (calib/mono_calibration.h writes it) or of OCamCalib's calib_results.txt.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/polynomial.h"

namespace hovs::calib {

// The "polynomial" object of a calibration.json, checked field by field (PolynomialModel::Check); `where` names it.
PolynomialModel<double> PolynomialFromJson(const nlohmann::json& polynomial, const std::string& where);

// OCamCalib's calib_results.txt (by extension .txt) or the polynomial model of a hovs calibration.json. Throws
// hovs::Error naming the file.
PolynomialModel<double> LoadPolynomialModelFile(const std::filesystem::path& path);

}  // namespace hovs::calib
