// OCamCalib's calib_results.txt, in its own layout: the direct polynomial (ss, ascending, a1 = 0), the inverse
// polynomial (invpol, ascending in theta), the centre as row then column (0-based, C convention), the affine
// c, d, e, and the image size as height then width. hovs' PolynomialModel stores exactly these semantics
// (polynomial.h), so the conversion is a relabelling.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/polynomial.h"
#include "core/rigid.h"

namespace hovs::calib {

std::string FormatOcamCalibResults(const PolynomialModel<double>& model);
// Throws hovs::Error naming the file and line for anything that is not this layout. Windows line endings are
// read. The valid annulus is not part of the format: hovs writes it on the inverse polynomial's comment line
// (OCamCalib's readers skip comment lines whole) and reads it back from there; other files get rho_min 0 and
// rho_max half the image diagonal.
PolynomialModel<double> ParseOcamCalibResults(const std::string& text, const std::string& source);
PolynomialModel<double> LoadOcamCalibResults(const std::filesystem::path& path);

// The board poses in the layout of OCamCalib's extrinsics (calib_data.RRfin in MATLAB): per image a 3 x 3 matrix
// [r1 r2 t] with [X; Y; Z] = RRfin [x; y; 1] for a board point (x, y) in millimetres and (X, Y, Z) in the frame of
// cam2world's rays (X along the rows, Y along the columns, Z = f(rho)), headed by the image's name. Written at
// full precision (%.17g): ParseOcamExtrinsics gives hovs' poses (mirror_from_board, metres) back exactly.
struct OcamExtrinsics {
  std::vector<std::string> images;
  std::vector<Rigid3d> mirror_from_board;
};
std::string FormatOcamExtrinsics(const OcamExtrinsics& poses);
// Throws hovs::Error naming the file and line for a matrix that is not 3 x 3 numbers or whose r1, r2 are not
// orthonormal.
OcamExtrinsics ParseOcamExtrinsics(const std::string& text, const std::string& source);

}  // namespace hovs::calib
