#include "calib/omnidir_io.h"

#include <opencv2/core.hpp>

#include <cmath>

#include "core/error.h"
#include "core/io.h"

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
cv::Mat ReadMat(const cv::FileStorage& fs, const std::string& key, int rows, int cols, const std::string& source) {
  const cv::FileNode n = fs[key];
  HOVS_REQUIRE(!n.empty(), source + ": " + key, "missing");
  cv::Mat m;
  if (n.isReal() || n.isInt()) {
    m = cv::Mat(1, 1, CV_64F, cv::Scalar(static_cast<double>(n)));
  } else {
    try {
      n >> m;
    } catch (const cv::Exception&) {
      throw Error(source + ": " + key, "not a matrix");
    }
  }
  HOVS_REQUIRE(!m.empty() && static_cast<int>(m.total()) == rows * cols, source + ": " + key, "expected a ", rows,
               " x ", cols, " matrix (got ", m.rows, " x ", m.cols, ")");
  m.convertTo(m, CV_64F);
  m = m.reshape(1, rows);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) HOVS_REQUIRE(std::isfinite(m.at<double>(r, c)), source + ": " + key, "not finite");
  return m;
}
}  // namespace

OmnidirFile ParseOmnidirYaml(const std::string& text, const std::string& source) {
  HOVS_REQUIRE(LooksLikeOmnidirYaml(text), source, "not an OpenCV FileStorage YAML file with a camera_matrix");
  cv::FileStorage fs;
  try {
    fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  } catch (const cv::Exception& e) {
    throw Error(source, std::string("unreadable FileStorage YAML: ") + e.what());
  }
  HOVS_REQUIRE(fs.isOpened(), source, "unreadable FileStorage YAML");
  OmnidirFile f;
  auto& m = f.model;
  for (const char* key : {"image_width", "image_height"})
    HOVS_REQUIRE(fs[key].isInt(), source + ": " + key, "missing or not an integer");
  m.width = static_cast<int>(fs["image_width"]), m.height = static_cast<int>(fs["image_height"]);
  HOVS_REQUIRE(m.width > 0 && m.height > 0, source + ": image_width/image_height", "must be positive");
  const cv::Mat K = ReadMat(fs, "camera_matrix", 3, 3, source);
  HOVS_REQUIRE(K.at<double>(1, 0) == 0 && K.at<double>(2, 0) == 0 && K.at<double>(2, 1) == 0 && K.at<double>(2, 2) == 1,
               source + ": camera_matrix", "must be [fx s cx; 0 fy cy; 0 0 1]");
  m.fx = K.at<double>(0, 0), m.skew = K.at<double>(0, 1), m.cx = K.at<double>(0, 2);
  m.fy = K.at<double>(1, 1), m.cy = K.at<double>(1, 2);
  HOVS_REQUIRE(m.fx > 0 && m.fy > 0, source + ": camera_matrix", "focal lengths must be positive");
  const cv::Mat D = ReadMat(fs, "distortion_coefficients", 1, 4, source);
  m.distortion = {D.at<double>(0), D.at<double>(1), D.at<double>(2), D.at<double>(3)};
  m.xi = ReadMat(fs, "xi", 1, 1, source).at<double>(0);
  HOVS_REQUIRE(m.xi >= 0, source + ": xi", "must be non-negative (got ", m.xi, ")");
  if (!fs["rms_px"].empty()) f.rms_px = static_cast<double>(fs["rms_px"]);
  if (!fs["annulus_px"].empty()) {
    const cv::Mat a = ReadMat(fs, "annulus_px", 1, 2, source);
    f.annulus_min = a.at<double>(0), f.annulus_max = a.at<double>(1);
    HOVS_REQUIRE(f.annulus_min >= 0 && f.annulus_max > f.annulus_min, source + ": annulus_px", "must be 0 <= min < max");
  }
  for (const char* name : {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"})
    if (!fs[std::string("stddev_") + name].empty()) f.stddev[name] = static_cast<double>(fs[std::string("stddev_") + name]);
  return f;
}

OmnidirFile LoadOmnidirYaml(const std::filesystem::path& path) {
  HOVS_REQUIRE(std::filesystem::exists(path), path.string(), "file not found");
  return ParseOmnidirYaml(ReadFile(path), path.string());
}

}  // namespace hovs::calib
