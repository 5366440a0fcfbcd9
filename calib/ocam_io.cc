#include "calib/ocam_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "core/io.h"

namespace hovs::calib {

namespace {
const std::string kRingText = "fitted over the calibrated ring, image radii ";
}  // namespace

std::string FormatOcamCalibResults(const PolynomialModel<double>& m) {
  m.Check("OCamCalib export");
  HOVS_REQUIRE(!m.inv_poly.empty(), "OCamCalib export", "the model has no inverse polynomial");
  HOVS_REQUIRE(!m.HasDecentering(), "OCamCalib export",
               "the model has decentering terms (p1, p2), which OCamCalib's calib_results.txt cannot hold: use "
               "calibration.json, or calibrate without --decentering");
  std::string out;
  char buf[64];
  out +=
      "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by "
      "cam2world\n\n";
  out += std::to_string(m.poly.size()) + " ";
  for (double a : m.poly) std::snprintf(buf, sizeof buf, "%e ", a), out += buf;
  // OCamCalib's C reader skips each comment as one whole line, so where the inverse is valid is said on the
  // comment's own line: extra lines would shift what it reads.
  std::snprintf(buf, sizeof buf, "%.2f to %.2f", m.rho_min, m.rho_max);
  out +=
      "\n\n#polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB). These are used by "
      "world2cam (" +
      kRingText + buf + " px from the centre; outside it world2cam extrapolates)\n\n";
  out += std::to_string(m.inv_poly.size()) + " ";
  for (double a : m.inv_poly) std::snprintf(buf, sizeof buf, "%f ", a), out += buf;
  out += "\n\n#center: \"row\" and \"column\", starting from 0 (C convention)\n\n";
  std::snprintf(buf, sizeof buf, "%f %f", m.cy, m.cx);
  out += buf;
  out += "\n\n#affine parameters \"c\", \"d\", \"e\"\n\n";
  std::snprintf(buf, sizeof buf, "%f %f %f", m.c, m.d, m.e);
  out += buf;
  out += "\n\n#image size: \"height\" and \"width\"\n\n";
  out += std::to_string(m.height) + " " + std::to_string(m.width) + "\n";
  return out;
}

PolynomialModel<double> ParseOcamCalibResults(const std::string& text, const std::string& source) {
  std::istringstream in(NormalisedText(text));
  std::string line;
  int lineno = 0;
  // The next data line (skipping comments and blank lines), as numbers.
  const auto data = [&](const char* what) {
    while (std::getline(in, line)) {
      ++lineno;
      // Windows line endings: a line holding only "\r" is blank, as OCamCalib's own C reader takes it.
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ls(line);
      std::vector<double> v;
      double x;
      while (ls >> x) v.push_back(x);
      HOVS_REQUIRE(ls.eof() && !v.empty() && std::all_of(v.begin(), v.end(), [](double y) { return std::isfinite(y); }),
                   source + ":" + std::to_string(lineno), "expected numbers for ", what);
      return v;
    }
    throw Error(source, std::string("missing ") + what);
  };
  PolynomialModel<double> m;
  auto ss = data("the direct polynomial");
  HOVS_REQUIRE(ss.size() >= 3 && ss[0] == static_cast<int>(ss.size()) - 1, source + ":" + std::to_string(lineno),
               "the direct polynomial's length does not match its coefficients");
  m.poly.assign(ss.begin() + 1, ss.end());
  auto inv = data("the inverse polynomial");
  HOVS_REQUIRE(inv.size() >= 2 && inv[0] == static_cast<int>(inv.size()) - 1, source + ":" + std::to_string(lineno),
               "the inverse polynomial's length does not match its coefficients");
  m.inv_poly.assign(inv.begin() + 1, inv.end());
  const auto centre = data("the centre");
  HOVS_REQUIRE(centre.size() == 2, source + ":" + std::to_string(lineno), "the centre needs row and column");
  m.cy = centre[0], m.cx = centre[1];
  const auto aff = data("the affine parameters");
  HOVS_REQUIRE(aff.size() == 3, source + ":" + std::to_string(lineno), "the affine parameters need c, d, e");
  m.c = aff[0], m.d = aff[1], m.e = aff[2];
  const auto size = data("the image size");
  HOVS_REQUIRE(size.size() == 2 && size[0] >= 1 && size[1] >= 1 && size[0] <= 65535 && size[1] <= 65535 &&
                   size[0] == std::floor(size[0]) && size[1] == std::floor(size[1]),
               source + ":" + std::to_string(lineno),
               "the image size needs height and width, whole numbers in 1..65535");
  m.height = static_cast<int>(size[0]), m.width = static_cast<int>(size[1]);
  m.rho_min = 0, m.rho_max = 0.5 * std::hypot(m.width, m.height);
  // hovs' own files say on the inverse's comment line where the model was calibrated: that ring is kept.
  const size_t ring = text.find(kRingText);
  double lo = 0, hi = 0;
  if (ring != std::string::npos && std::sscanf(text.c_str() + ring + kRingText.size(), "%lf to %lf", &lo, &hi) == 2 &&
      std::isfinite(lo) && std::isfinite(hi) && lo >= 0 && hi > lo && hi <= 2 * std::hypot(m.width, m.height))
    m.rho_min = lo, m.rho_max = hi;
  m.Check(source);
  return m;
}

PolynomialModel<double> LoadOcamCalibResults(const std::filesystem::path& path) {
  return ParseOcamCalibResults(ReadFile(path), path.string());
}

namespace {
// OCamCalib's camera frame swaps hovs' first two axes (polynomial.h): rows first, then columns.
Eigen::Matrix3d OcamFromMirror() {
  Eigen::Matrix3d p;
  p << 0, 1, 0, 1, 0, 0, 0, 0, 1;
  return p;
}
}  // namespace

std::string FormatOcamExtrinsics(const OcamExtrinsics& poses) {
  HOVS_REQUIRE(poses.images.size() == poses.mirror_from_board.size(), "OCamCalib extrinsics",
               "one image name per pose");
  std::string out =
      "#extrinsic parameters (calib_data.RRfin in MATLAB), one 3 x 3 matrix [r1 r2 t] per image:\n"
      "#[X; Y; Z] = RRfin * [x; y; 1], board point (x, y) in millimetres, (X, Y, Z) in the frame of cam2world's\n"
      "#rays (X along the rows, Y along the columns, Z = f(rho)) of calib_results.txt\n";
  char buf[96];
  for (size_t i = 0; i < poses.images.size(); ++i) {
    const Rigid3d& pose = poses.mirror_from_board[i];
    const Eigen::Matrix3d r = OcamFromMirror() * pose.rotation.toRotationMatrix();
    const Eigen::Vector3d t = OcamFromMirror() * pose.translation * 1000.0;
    out += "\n#image " + std::to_string(i + 1) + ": " + poses.images[i] + "\n";
    for (int row = 0; row < 3; ++row)
      std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", r(row, 0), r(row, 1), t(row)), out += buf;
  }
  return out;
}

OcamExtrinsics ParseOcamExtrinsics(const std::string& text, const std::string& source) {
  OcamExtrinsics out;
  std::istringstream in(NormalisedText(text));
  std::string line, name;
  int lineno = 0;
  std::vector<double> m;
  const std::string header = "#image ";
  while (std::getline(in, line)) {
    ++lineno;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    const std::string where = source + ":" + std::to_string(lineno);
    if (line.rfind(header, 0) == 0) {
      HOVS_REQUIRE(m.empty(), where, "the previous image's matrix has ", m.size() / 3, " of its 3 rows");
      const size_t colon = line.find(": ");
      HOVS_REQUIRE(colon != std::string::npos, where, "expected '#image N: NAME'");
      name = line.substr(colon + 2);
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    HOVS_REQUIRE(!name.empty(), where, "a matrix row before any '#image N: NAME' line");
    std::istringstream ls(line);
    std::vector<double> row;
    double x;
    while (ls >> x) row.push_back(x);
    HOVS_REQUIRE(
        ls.eof() && row.size() == 3 && std::all_of(row.begin(), row.end(), [](double y) { return std::isfinite(y); }),
        where, "expected a row of 3 finite numbers of RRfin");
    m.insert(m.end(), row.begin(), row.end());
    if (m.size() < 9) continue;
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    for (int k = 0; k < 3; ++k) r(k, 0) = m[3 * k], r(k, 1) = m[3 * k + 1], t(k) = m[3 * k + 2];
    const Eigen::Matrix3d back = OcamFromMirror();  // its own inverse
    Eigen::Matrix3d rot;
    rot.col(0) = back * r.col(0), rot.col(1) = back * r.col(1);
    HOVS_REQUIRE(std::abs(rot.col(0).norm() - 1) < 1e-6 && std::abs(rot.col(1).norm() - 1) < 1e-6 &&
                     std::abs(rot.col(0).dot(rot.col(1))) < 1e-6,
                 where, "r1 and r2 of ", name, " are not orthonormal");
    rot.col(2) = rot.col(0).cross(rot.col(1));
    out.images.push_back(name);
    out.mirror_from_board.emplace_back(Eigen::Quaterniond(rot).normalized(), back * t / 1000.0);
    m.clear(), name.clear();
  }
  HOVS_REQUIRE(m.empty(), source, "the last image's matrix has ", m.size() / 3, " of its 3 rows");
  HOVS_REQUIRE(!out.images.empty(), source, "no '#image N: NAME' matrix: not an OCamCalib extrinsics file");
  return out;
}

}  // namespace hovs::calib
