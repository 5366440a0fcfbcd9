// OCamCalib's calib_results.txt, in its own layout: the direct polynomial (ss, ascending, a1 = 0), the inverse
// polynomial (invpol, ascending in theta), the centre as row then column (0-based, C convention), the affine
// c, d, e, and the image size as height then width. hovs' PolynomialModel stores exactly these semantics
// (polynomial.h), so the conversion is a relabelling.
#pragma once

#include <filesystem>
#include <string>

#include "core/polynomial.h"

namespace hovs::calib {

std::string FormatOcamCalibResults(const PolynomialModel<double>& model);
// Throws hovs::Error naming the file and line for anything that is not this layout. Windows line endings are
// read. The valid annulus is not part of the format: hovs writes it on the inverse polynomial's comment line
// (OCamCalib's readers skip comment lines whole) and reads it back from there; other files get rho_min 0 and
// rho_max half the image diagonal.
PolynomialModel<double> ParseOcamCalibResults(const std::string& text, const std::string& source);
PolynomialModel<double> LoadOcamCalibResults(const std::filesystem::path& path);

}  // namespace hovs::calib
