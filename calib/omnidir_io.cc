#include "calib/omnidir_io.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <vector>

#include "core/error.h"
#include "core/io.h"
#include "core/yaml_reader.h"

namespace hovs::calib {

namespace {

// A pose between hovs' mirror frame and omnidir's camera frame, (x, y, -z): F R F, F t with F = diag(1, 1, -1)
// (its own inverse).
Rigid3d FlipZ(const Rigid3d& p) {
  const Eigen::Matrix3d F = Eigen::Vector3d(1, 1, -1).asDiagonal();
  const Eigen::Matrix3d R = F * p.rotation.toRotationMatrix() * F;
  return Rigid3d(Eigen::Quaterniond(R), F * p.translation);
}

// One board per row: rvec, tvec (omnidir's frame) -> cam_from_board (mirror frame).
std::vector<Rigid3d> PosesFromRows(const std::vector<double>& v, const std::string& where) {
  std::vector<Rigid3d> poses;
  for (size_t i = 0; i + 6 <= v.size(); i += 6) {
    const Vec3d r(v[i], v[i + 1], v[i + 2]), t(v[i + 3], v[i + 4], v[i + 5]);
    HOVS_REQUIRE(r.allFinite() && t.allFinite() && r.norm() < 100 && t.norm() < 1e6, where, "row ", i / 6,
                 " is not a pose (rvec, tvec)");
    const double angle = r.norm();
    const Eigen::Quaterniond q(angle > 0 ? Eigen::AngleAxisd(angle, r / angle) : Eigen::AngleAxisd::Identity());
    poses.push_back(FlipZ(Rigid3d(q, t)));
  }
  return poses;
}

// What every form shares after its keys are read: the size's range, the model's check.
void Finish(OmnidirFile* f, const std::string& where) {
  auto& m = f->model;
  HOVS_REQUIRE((m.width == 0) == (m.height == 0), where, "image_width and image_height come together");
  HOVS_REQUIRE(m.width >= 0 && m.height >= 0 && m.width <= 65535 && m.height <= 65535, where,
               "the image size must be 1..65535 pixels a side");
  HOVS_REQUIRE(f->annulus_max == 0 || (f->annulus_min >= 0 && f->annulus_max > f->annulus_min), where,
               "annulus_px must be 0 <= min < max");
  m.Check(where);
}

}  // namespace

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
  fs << "xi" << m.xi;
  if (!f.cam_from_board.empty()) {
    fs.writeComment("extrinsic_parameters: one board per row, rvec then tvec (m), omnidir's camera frame");
    fs << "nFrames" << static_cast<int>(f.cam_from_board.size());
    cv::Mat rt(static_cast<int>(f.cam_from_board.size()), 6, CV_64F);
    for (int i = 0; i < rt.rows; ++i) {
      const Rigid3d p = FlipZ(f.cam_from_board[i]);
      const Eigen::AngleAxisd aa(p.rotation);
      const Vec3d r = aa.angle() * aa.axis();
      for (int k = 0; k < 3; ++k) rt.at<double>(i, k) = r(k), rt.at<double>(i, 3 + k) = p.translation(k);
    }
    fs << "extrinsic_parameters" << rt;
  }
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

// A matrix of any number of rows of `cols` numbers (at most 100,000 rows), row-major.
std::vector<double> ReadRows(const YamlReader& r, const YAML::Node& root, const std::string& key, int cols) {
  const YAML::Node n = root[key];
  HOVS_REQUIRE(n.IsMap() && n["rows"] && n["cols"], r.Where(root, key), "expected a matrix (rows, cols, dt, data)");
  const int rows = r.Integer(n["rows"], key + ".rows");
  HOVS_REQUIRE(rows >= 0 && rows <= 100000, r.Where(n, key), "expected 0..100000 rows (got ", rows, ")");
  return ReadMatrix(r, root, key, rows, cols);
}

OmnidirFile ParseOmnidirYamlUnguarded(const std::string& text, const std::string& source) {
  HOVS_REQUIRE(LooksLikeOmnidirYaml(text), source, "not an OpenCV FileStorage YAML file with a camera_matrix");
  const YamlReader r(source);
  const size_t first_line = text.find('\n');
  // Line numbers in errors count from the file's first line: the directive line is kept as a blank one.
  const YAML::Node root = r.Load(first_line == std::string::npos ? std::string() : "\n" + text.substr(first_line + 1));
  HOVS_REQUIRE(root.IsMap(), source, "expected a mapping of the model's parameters");
  // hovs' keys and the omni_calibration sample's.
  std::set<std::string> known = {
      "image_width", "image_height", "camera_matrix",        "distortion_coefficients", "xi",    "rms_px",
      "annulus_px",  "nFrames",      "extrinsic_parameters", "calibration_time",        "flags", "used_imgs",
      "rms",         "image_points"};
  for (const char* name : {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"})
    known.insert(std::string("stddev_") + name);
  r.OnlyKeys(root, "", known);
  OmnidirFile f;
  auto& m = f.model;
  if (root["image_width"]) m.width = r.Integer(root["image_width"], "image_width");
  if (root["image_height"]) m.height = r.Integer(root["image_height"], "image_height");
  const auto K = ReadMatrix(r, root, "camera_matrix", 3, 3);
  HOVS_REQUIRE(K[3] == 0 && K[6] == 0 && K[7] == 0 && K[8] == 1, r.Where(root["camera_matrix"], "camera_matrix"),
               "must be [fx s cx; 0 fy cy; 0 0 1]");
  m.fx = K[0], m.skew = K[1], m.cx = K[2], m.fy = K[4], m.cy = K[5];
  const auto D = ReadMatrix(r, root, "distortion_coefficients", 1, 4);
  m.distortion = {D[0], D[1], D[2], D[3]};
  m.xi = ReadMatrix(r, root, "xi", 1, 1)[0];
  if (root["rms"]) f.rms_px = r.Number(root["rms"], "rms");
  if (root["rms_px"]) f.rms_px = r.Number(root["rms_px"], "rms_px");
  if (root["annulus_px"]) {
    const auto a = ReadMatrix(r, root, "annulus_px", 1, 2);
    f.annulus_min = a[0], f.annulus_max = a[1];
  }
  if (root["extrinsic_parameters"])
    f.cam_from_board = PosesFromRows(ReadRows(r, root, "extrinsic_parameters", 6),
                                     r.Where(root["extrinsic_parameters"], "extrinsic_parameters"));
  for (const char* name : {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"})
    if (root[std::string("stddev_") + name])
      f.stddev[name] = r.Number(root[std::string("stddev_") + name], std::string("stddev_") + name);
  Finish(&f, source);
  return f;
}

}  // namespace

OmnidirFile ParseOmnidirYaml(const std::string& text, const std::string& source) {
  return WithYamlErrors(source, [&] { return ParseOmnidirYamlUnguarded(text, source); });
}

bool LooksLikeOmnidirXml(const std::string& text) {
  const size_t start = text.find_first_not_of(" \t\r\n");
  return start != std::string::npos && text.compare(start, 5, "<?xml") == 0 &&
         text.find("<opencv_storage>") != std::string::npos && text.find("<camera_matrix") != std::string::npos;
}

namespace {

// The XML form, read by hand rather than by cv::FileStorage (whose parsers take gigabytes on some malformed
// files, as the YAML reader above notes): the top level of <opencv_storage> is a list of elements, each holding
// text (a number, a string, a sequence) or child elements (an opencv-matrix: rows, cols, dt, data). Deeper
// nesting, unclosed or mismatched tags are errors.
struct XmlNode {
  std::string text;
  std::map<std::string, XmlNode> children;
};

class XmlReader {
 public:
  XmlReader(const std::string& text, const std::string& source) : t_(text), source_(source) {}

  std::map<std::string, XmlNode> Storage() {
    pos_ = t_.find("<opencv_storage>");
    HOVS_REQUIRE(pos_ != std::string::npos, source_, "no <opencv_storage> element");
    pos_ += 16;
    std::map<std::string, XmlNode> top = Children("opencv_storage", 0);
    return top;
  }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    const size_t line = 1 + std::count(t_.begin(), t_.begin() + std::min(pos_, t_.size()), '\n');
    throw Error(source_ + ":" + std::to_string(line), what);
  }
  void SkipSpaceAndComments() {
    for (;;) {
      while (pos_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[pos_]))) ++pos_;
      if (t_.compare(pos_, 4, "<!--") != 0) return;
      const size_t end = t_.find("-->", pos_ + 4);
      if (end == std::string::npos) Fail("unclosed comment");
      pos_ = end + 3;
    }
  }
  // Elements up to the closing tag of `parent`.
  std::map<std::string, XmlNode> Children(const std::string& parent, int depth) {
    std::map<std::string, XmlNode> out;
    for (;;) {
      SkipSpaceAndComments();
      if (pos_ >= t_.size()) Fail("<" + parent + "> is not closed");
      if (t_.compare(pos_, 2, "</") == 0) {
        const std::string close = "</" + parent + ">";
        if (t_.compare(pos_, close.size(), close) != 0) Fail("expected " + close);
        pos_ += close.size();
        return out;
      }
      if (t_[pos_] != '<') Fail("expected an element inside <" + parent + ">");
      const size_t name_end = t_.find_first_of(" \t\r\n/>", pos_ + 1);
      if (name_end == std::string::npos || name_end == pos_ + 1) Fail("malformed tag");
      const std::string name = t_.substr(pos_ + 1, name_end - pos_ - 1);
      const size_t tag_end = t_.find('>', name_end);
      if (tag_end == std::string::npos) Fail("unclosed tag <" + name + ">");
      XmlNode node;
      pos_ = tag_end + 1;
      if (t_[tag_end - 1] != '/') {  // not <name/>
        SkipSpaceAndComments();
        if (pos_ < t_.size() && t_[pos_] == '<' && t_.compare(pos_, 2, "</") != 0) {
          if (depth >= 1) Fail("<" + name + "> nests deeper than an OpenCV matrix");
          node.children = Children(name, depth + 1);
        } else {
          const std::string close = "</" + name + ">";
          const size_t end = t_.find(close, pos_);
          if (end == std::string::npos) Fail("<" + name + "> is not closed");
          node.text = t_.substr(pos_, end - pos_);
          pos_ = end + close.size();
        }
      }
      if (!out.emplace(name, std::move(node)).second) Fail("<" + name + "> appears twice");
    }
  }

  const std::string& t_;
  std::string source_;
  size_t pos_ = 0;
};

std::vector<double> XmlNumbers(const std::string& text, const std::string& where) {
  std::vector<double> v;
  const char* p = text.c_str();
  const char* end = p + text.size();
  while (p < end) {
    while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (p >= end) break;
    char* next = nullptr;
    const double x = std::strtod(p, &next);
    HOVS_REQUIRE(next != p && std::isfinite(x), where, "expected numbers");
    HOVS_REQUIRE(v.size() < 600000, where, "too many numbers");
    v.push_back(x);
    p = next;
  }
  return v;
}

// A node as numbers: a scalar, or an opencv-matrix of rows x cols (rows -1: any number of rows).
std::vector<double> XmlMatrix(const std::map<std::string, XmlNode>& top, const std::string& key, int rows, int cols,
                              const std::string& source) {
  const std::string where = source + " (" + key + ")";
  const auto it = top.find(key);
  HOVS_REQUIRE(it != top.end(), where, "missing");
  const XmlNode& n = it->second;
  if (n.children.empty()) {
    const auto v = XmlNumbers(n.text, where);
    HOVS_REQUIRE(v.size() == 1 && rows * cols == 1, where, "expected a ", rows, " x ", cols, " matrix");
    return v;
  }
  for (const char* k : {"rows", "cols", "data"})
    HOVS_REQUIRE(n.children.count(k), where, "an opencv-matrix needs rows, cols, dt and data");
  const auto r = XmlNumbers(n.children.at("rows").text, where + ".rows");
  const auto c = XmlNumbers(n.children.at("cols").text, where + ".cols");
  HOVS_REQUIRE(
      r.size() == 1 && c.size() == 1 && c[0] == cols && r[0] >= 1 && r[0] <= 100000 && (rows < 0 || r[0] == rows),
      where, "expected a ", rows < 0 ? std::string("N") : std::to_string(rows), " x ", cols, " matrix");
  const auto v = XmlNumbers(n.children.at("data").text, where + ".data");
  HOVS_REQUIRE(v.size() == size_t(r[0]) * cols, where, "expected ", size_t(r[0]) * cols, " numbers");
  return v;
}

}  // namespace

OmnidirFile ParseOmnidirXml(const std::string& text, const std::string& source) {
  HOVS_REQUIRE(text.size() <= (size_t(64) << 20), source, "larger than 64 MB: not a camera file");
  HOVS_REQUIRE(LooksLikeOmnidirXml(text), source, "not an OpenCV FileStorage XML file with a camera_matrix");
  const std::map<std::string, XmlNode> top = XmlReader(text, source).Storage();
  OmnidirFile f;
  auto& m = f.model;
  const auto integer = [&](const char* key) {
    const auto v = XmlMatrix(top, key, 1, 1, source);
    HOVS_REQUIRE(v[0] == std::floor(v[0]) && std::abs(v[0]) <= 1e6, source + " (" + key + ")", "expected an integer");
    return static_cast<int>(v[0]);
  };
  if (top.count("image_width")) m.width = integer("image_width");
  if (top.count("image_height")) m.height = integer("image_height");
  const auto K = XmlMatrix(top, "camera_matrix", 3, 3, source);
  HOVS_REQUIRE(K[3] == 0 && K[6] == 0 && K[7] == 0 && K[8] == 1, source + " (camera_matrix)",
               "must be [fx s cx; 0 fy cy; 0 0 1]");
  m.fx = K[0], m.skew = K[1], m.cx = K[2], m.fy = K[4], m.cy = K[5];
  const auto D = XmlMatrix(top, "distortion_coefficients", 1, 4, source);
  m.distortion = {D[0], D[1], D[2], D[3]};
  m.xi = XmlMatrix(top, "xi", 1, 1, source)[0];
  if (top.count("rms")) f.rms_px = XmlMatrix(top, "rms", 1, 1, source)[0];
  if (top.count("extrinsic_parameters"))
    f.cam_from_board =
        PosesFromRows(XmlMatrix(top, "extrinsic_parameters", -1, 6, source), source + " (extrinsic_parameters)");
  Finish(&f, source);
  return f;
}

OmnidirFile LoadOmnidirYaml(const std::filesystem::path& path) {
  RequireFile(path, "omnidir file");
  const std::string text = ReadFile(path);
  if (LooksLikeOmnidirXml(text)) return ParseOmnidirXml(text, path.string());
  return ParseOmnidirYaml(text, path.string());
}

UnifiedModel<double> WithImageSize(const OmnidirFile& file, int width, int height, const std::string& source) {
  UnifiedModel<double> m = file.model;
  const bool in_file = m.width > 0, given = width > 0 && height > 0;
  HOVS_REQUIRE(in_file || given, source,
               "has no image_width / image_height (OpenCV's omni_calibration sample writes none): give the image "
               "size (hovs convert --image-size WxH, or image_size= in Python)");
  if (in_file && given)
    HOVS_REQUIRE(m.width == width && m.height == height, source, "is for ", m.width, " x ", m.height, " images, not ",
                 width, " x ", height);
  if (!in_file) {
    m.width = width, m.height = height;
    m.Check(source);
  }
  return m;
}

}  // namespace hovs::calib
