#include "calib/omnidir_io.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <set>
#include <vector>

#include "core/error.h"
#include "core/io.h"
#include "core/yaml_reader.h"

namespace hovs::calib {

std::string FormatOmnidirYaml(const OmnidirFile& f) {
  const auto& m = f.model;
  m.Check("omnidir export");
  HOVS_REQUIRE(m.width > 0 && m.height > 0, "omnidir export", "the model has no image size");
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs.writeComment("unified (Mei) model, OpenCV omnidir parameter names; written by hovs calibrate");
  fs.writeComment("frame: omnidir's camera frame = (x, y, -z) of the hovs mirror frame; pixels 0-based");
  fs << "image_width" << m.width << "image_height" << m.height;
  const cv::Matx33d K(m.fx, m.skew, m.cx, 0, m.fy, m.cy, 0, 0, 1);
  fs << "camera_matrix" << cv::Mat(K);
  const cv::Matx14d D(m.distortion.k1, m.distortion.k2, m.distortion.p1, m.distortion.p2);
  fs << "distortion_coefficients" << cv::Mat(D);
  fs << "xi" << cv::Mat(1, 1, CV_64F, cv::Scalar(m.xi));
  if (f.rms_px >= 0) fs << "rms_px" << f.rms_px;
  if (f.annulus_max > 0) fs << "annulus_px" << cv::Mat(cv::Matx12d(f.annulus_min, f.annulus_max));
  for (const auto& [name, value] : f.stddev) fs << "stddev_" + name << value;
  return fs.releaseAndGetString();
}

bool LooksLikeOmnidirYaml(const std::string& text) {
  return text.rfind("%YAML:1.0", 0) == 0 && text.find("camera_matrix") != std::string::npos;
}

namespace {

// The reader: yaml-cpp on the text after the "%YAML:1.0" directive (OpenCV's own spelling, which YAML 1.2
// parsers refuse), not cv::FileStorage, whose parser loops and takes gigabytes on some malformed files (a
// matrix whose "cols:" holds another key). The format is a mapping of scalars and !!opencv-matrix mappings
// (rows, cols, dt, data).
std::vector<double> ReadMatrix(const YamlReader& r, const YAML::Node& root, const std::string& key, int rows,
                               int cols) {
  const YAML::Node n = root[key];
  HOVS_REQUIRE(n.IsDefined() && !n.IsNull(), r.Where(root, key), "missing");
  if (n.IsScalar()) {
    HOVS_REQUIRE(rows * cols == 1, r.Where(n, key), "expected a ", rows, " x ", cols, " matrix");
    return {r.Number(n, key)};
  }
  r.OnlyKeys(n, key, {"rows", "cols", "dt", "data"});
  YAML::Node nr, nc, data;
  const int got_rows = r.Integer(r.Require(n, key, "rows", &nr), key + ".rows");
  const int got_cols = r.Integer(r.Require(n, key, "cols", &nc), key + ".cols");
  HOVS_REQUIRE(got_rows * got_cols == rows * cols && got_rows > 0, r.Where(n, key), "expected a ", rows, " x ", cols,
               " matrix (got ", got_rows, " x ", got_cols, ")");
  r.Require(n, key, "data", &data);
  HOVS_REQUIRE(data.IsSequence() && static_cast<int>(data.size()) == rows * cols, r.Where(data, key + ".data"),
               "expected ", rows * cols, " numbers");
  std::vector<double> v;
  for (size_t k = 0; k < data.size(); ++k) v.push_back(r.Number(data[k], key + ".data"));
  return v;
}

OmnidirFile ParseOmnidirYamlUnguarded(const std::string& text, const std::string& source) {
  HOVS_REQUIRE(LooksLikeOmnidirYaml(text), source, "not an OpenCV FileStorage YAML file with a camera_matrix");
  const YamlReader r(source);
  const size_t first_line = text.find('\n');
  // Line numbers in errors count from the file's first line: the directive line is kept as a blank one.
  const YAML::Node root = r.Load(first_line == std::string::npos ? std::string() : "\n" + text.substr(first_line + 1));
  HOVS_REQUIRE(root.IsMap(), source, "expected a mapping of the model's parameters");
  std::set<std::string> known = {"image_width", "image_height", "camera_matrix", "distortion_coefficients",
                                 "xi",          "rms_px",       "annulus_px"};
  for (const char* name : {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"})
    known.insert(std::string("stddev_") + name);
  r.OnlyKeys(root, "", known);
  OmnidirFile f;
  auto& m = f.model;
  YAML::Node w, h;
  m.width = r.Integer(r.Require(root, "", "image_width", &w), "image_width");
  m.height = r.Integer(r.Require(root, "", "image_height", &h), "image_height");
  HOVS_REQUIRE(m.width > 0 && m.height > 0 && m.width <= 65535 && m.height <= 65535, r.Where(root, "image_width"),
               "the image size must be 1..65535 pixels a side");
  const auto K = ReadMatrix(r, root, "camera_matrix", 3, 3);
  HOVS_REQUIRE(K[3] == 0 && K[6] == 0 && K[7] == 0 && K[8] == 1, r.Where(root["camera_matrix"], "camera_matrix"),
               "must be [fx s cx; 0 fy cy; 0 0 1]");
  m.fx = K[0], m.skew = K[1], m.cx = K[2], m.fy = K[4], m.cy = K[5];
  const auto D = ReadMatrix(r, root, "distortion_coefficients", 1, 4);
  m.distortion = {D[0], D[1], D[2], D[3]};
  m.xi = ReadMatrix(r, root, "xi", 1, 1)[0];
  if (root["rms_px"]) f.rms_px = r.Number(root["rms_px"], "rms_px");
  if (root["annulus_px"]) {
    const auto a = ReadMatrix(r, root, "annulus_px", 1, 2);
    f.annulus_min = a[0], f.annulus_max = a[1];
    HOVS_REQUIRE(f.annulus_min >= 0 && f.annulus_max > f.annulus_min, r.Where(root["annulus_px"], "annulus_px"),
                 "must be 0 <= min < max");
  }
  for (const char* name : {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"})
    if (root[std::string("stddev_") + name])
      f.stddev[name] = r.Number(root[std::string("stddev_") + name], std::string("stddev_") + name);
  m.Check(source);
  return f;
}

}  // namespace

OmnidirFile ParseOmnidirYaml(const std::string& text, const std::string& source) {
  return WithYamlErrors(source, [&] { return ParseOmnidirYamlUnguarded(text, source); });
}

OmnidirFile LoadOmnidirYaml(const std::filesystem::path& path) {
  HOVS_REQUIRE(std::filesystem::exists(path), path.string(), "file not found");
  return ParseOmnidirYaml(ReadFile(path), path.string());
}

}  // namespace hovs::calib
