#include "calib/camera_formats.h"

#include <algorithm>
#include <cctype>

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/format.h"
#include "core/yaml_reader.h"

namespace hovs::calib {
namespace {

std::string List(const std::vector<double>& v) {
  std::string s = "[";
  for (size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + FormatNumber("%.17g", v[k]);
  return s + "]";
}

std::vector<double> ReadList(const YamlReader& r, const YAML::Node& map, const std::string& path,
                             const std::string& key, size_t n) {
  YAML::Node node;
  r.Require(map, path, key, &node);
  HOVS_REQUIRE(node.IsSequence() && node.size() == n, r.Where(node, path + "." + key), "expected ", n, " numbers");
  std::vector<double> v;
  for (size_t k = 0; k < n; ++k) v.push_back(r.Number(node[k], path + "." + key));
  return v;
}

size_t IntrinsicsCount(const std::string& model) {
  return model == "omni" ? 5 : model == "ds" || model == "eucm" ? 6 : model == "pinhole" ? 4 : 0;
}
size_t DistortionCount(const std::string& model) {
  return model == "radtan" || model == "equidistant" ? 4 : model == "none" ? 0 : 99;
}

}  // namespace

KalibrCamera KalibrFromUnified(const UnifiedModel<double>& m) {
  HOVS_REQUIRE(m.skew == 0, "Kalibr camchain", "Kalibr's omni model has no skew (the model's is ", m.skew, ")");
  KalibrCamera c;
  c.intrinsics = {m.xi, m.fx, m.fy, m.cx, m.cy};
  c.distortion = {m.distortion.k1, m.distortion.k2, m.distortion.p1, m.distortion.p2};
  c.width = m.width, c.height = m.height;
  return c;
}

KalibrCamera KalibrFromRefit(const Refit& r, int width, int height) {
  if (r.kind == "omni") return KalibrFromUnified(*r.unified);
  KalibrCamera c;
  c.width = width, c.height = height;
  if (r.kind == "kb") {
    c.camera_model = "pinhole", c.distortion_model = "equidistant";
    c.intrinsics.assign(r.values.begin(), r.values.begin() + 4);
    c.distortion.assign(r.values.begin() + 4, r.values.end());
  } else {
    c.camera_model = r.kind, c.distortion_model = "none";
    c.intrinsics = r.values;
  }
  return c;
}

std::string FormatBasaltCalibration(const std::vector<KalibrCamera>& cams) {
  const auto pose = [](const Eigen::Matrix4d& T) {
    const Eigen::Quaterniond q(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
    return nlohmann::ordered_json{{"px", T(0, 3)}, {"py", T(1, 3)}, {"pz", T(2, 3)}, {"qx", q.x()},
                                  {"qy", q.y()},   {"qz", q.z()},   {"qw", q.w()}};
  };
  nlohmann::ordered_json v, poses = nlohmann::ordered_json::array(), intr = nlohmann::ordered_json::array(),
                            res = nlohmann::ordered_json::array();
  Eigen::Matrix4d body_from_cam = Eigen::Matrix4d::Identity();
  for (size_t i = 0; i < cams.size(); ++i) {
    const KalibrCamera& c = cams[i];
    const std::string where = "Basalt export (cam" + std::to_string(i) + ")";
    if (i > 0) {
      HOVS_REQUIRE(c.T_cn_cnm1.has_value(), where, "needs its pose relative to the previous camera");
      body_from_cam = body_from_cam * c.T_cn_cnm1->inverse();
    }
    poses.push_back(pose(body_from_cam));
    const auto& k = c.intrinsics;
    nlohmann::ordered_json in;
    if (c.camera_model == "ds" && k.size() == 6) {
      in = {{"camera_type", "ds"},
            {"intrinsics", {{"fx", k[2]}, {"fy", k[3]}, {"cx", k[4]}, {"cy", k[5]}, {"xi", k[0]}, {"alpha", k[1]}}}};
    } else if (c.camera_model == "eucm" && k.size() == 6) {
      in = {{"camera_type", "eucm"},
            {"intrinsics", {{"fx", k[2]}, {"fy", k[3]}, {"cx", k[4]}, {"cy", k[5]}, {"alpha", k[0]}, {"beta", k[1]}}}};
    } else if (c.camera_model == "pinhole" && c.distortion_model == "equidistant" && k.size() == 4 &&
               c.distortion.size() == 4) {
      const auto& d = c.distortion;
      in = {{"camera_type", "kb4"},
            {"intrinsics",
             {{"fx", k[0]},
              {"fy", k[1]},
              {"cx", k[2]},
              {"cy", k[3]},
              {"k1", d[0]},
              {"k2", d[1]},
              {"k3", d[2]},
              {"k4", d[3]}}}};
    } else {
      throw Error(where, "Basalt has no " + c.camera_model + " + " + c.distortion_model +
                             " camera: refit to ds, eucm or kb (hovs convert --to basalt refits to ds)");
    }
    intr.push_back(in);
    res.push_back({c.width, c.height});
  }
  const auto identity = pose(Eigen::Matrix4d::Identity());
  v["T_imu_cam"] = poses;
  v["intrinsics"] = intr;
  v["resolution"] = res;
  v["vignette"] = nlohmann::ordered_json::array();
  v["calib_accel_bias"] = std::vector<double>(9, 0.0);
  v["calib_gyro_bias"] = std::vector<double>(12, 0.0);
  v["imu_update_rate"] = 200.0;
  v["accel_noise_std"] = 0.0, v["gyro_noise_std"] = 0.0, v["accel_bias_std"] = 0.0, v["gyro_bias_std"] = 0.0;
  v["T_mocap_world"] = identity, v["T_imu_marker"] = identity;
  v["mocap_time_offset_ns"] = 0, v["mocap_to_imu_offset_ns"] = 0, v["cam_time_offset_ns"] = 0;
  return nlohmann::ordered_json{{"value0", v}}.dump(4) + "\n";
}

Eigen::Matrix4d ToolsFromMirrorPose(const Rigid3d& T, double gamma_left, double gamma_right) {
  // A point's tools coordinates: Rz(gamma) S its mirror coordinates (S and Rz commute).
  const Eigen::Matrix3d S = Eigen::Vector3d(1, 1, -1).asDiagonal();
  const Eigen::Matrix3d Rl = Eigen::AngleAxisd(gamma_left, Vec3d::UnitZ()).toRotationMatrix() * S;
  const Eigen::Matrix3d Rr = Eigen::AngleAxisd(gamma_right, Vec3d::UnitZ()).toRotationMatrix() * S;
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = Rr * T.rotation.toRotationMatrix() * Rl.inverse();
  M.topRightCorner<3, 1>() = Rr * T.translation;
  return M;
}

std::string FormatKalibrCamchain(const std::vector<KalibrCamera>& cams) {
  std::string s = "# Kalibr camchain written by hovs (camera frame: (x, y, -z) of hovs' mirror frame)\n";
  for (size_t i = 0; i < cams.size(); ++i) {
    const auto& c = cams[i];
    s += "cam" + std::to_string(i) + ":\n";
    if (c.T_cn_cnm1) {
      s += "  T_cn_cnm1:\n";
      for (int r = 0; r < 4; ++r) {
        std::vector<double> row;
        for (int k = 0; k < 4; ++k) row.push_back((*c.T_cn_cnm1)(r, k));
        s += "  - " + List(row) + "\n";
      }
    }
    s += "  camera_model: " + c.camera_model + "\n";
    s += "  intrinsics: " + List(c.intrinsics) + "\n";
    s += "  distortion_model: " + c.distortion_model + "\n";
    s += "  distortion_coeffs: " + List(c.distortion) + "\n";
    s += "  resolution: [" + std::to_string(c.width) + ", " + std::to_string(c.height) + "]\n";
    s += "  rostopic: " + (c.rostopic.empty() ? "/cam" + std::to_string(i) + "/image_raw" : c.rostopic) + "\n";
  }
  return s;
}

bool LooksLikeKalibrCamchain(const std::string& text) {
  return text.find("cam0:") != std::string::npos && text.find("camera_model") != std::string::npos;
}

std::vector<KalibrCamera> ParseKalibrCamchain(const std::string& text, const std::string& source) {
  return WithYamlErrors(source, [&] {
    const YamlReader r(source);
    const YAML::Node root = r.Load(text);
    HOVS_REQUIRE(root.IsMap() && root["cam0"], source, "not a Kalibr camchain (no cam0)");
    std::vector<KalibrCamera> out;
    for (int i = 0; root["cam" + std::to_string(i)]; ++i) {
      const std::string key = "cam" + std::to_string(i);
      const YAML::Node c = root[key];
      HOVS_REQUIRE(c.IsMap(), r.Where(c, key), "expected a mapping");
      r.OnlyKeys(c, key,
                 {"camera_model", "intrinsics", "distortion_model", "distortion_coeffs", "resolution", "rostopic",
                  "T_cn_cnm1", "T_cam_imu", "timeshift_cam_imu", "cam_overlaps"});
      KalibrCamera k;
      YAML::Node n;
      k.camera_model = r.String(r.Require(c, key, "camera_model", &n), key + ".camera_model");
      HOVS_REQUIRE(IntrinsicsCount(k.camera_model) > 0, r.Where(n, key + ".camera_model"), "unknown camera model '",
                   k.camera_model, "' (known: omni, ds, eucm, pinhole)");
      k.intrinsics = ReadList(r, c, key, "intrinsics", IntrinsicsCount(k.camera_model));
      k.distortion_model = c["distortion_model"] ? r.String(c["distortion_model"], key + ".distortion_model") : "none";
      HOVS_REQUIRE(DistortionCount(k.distortion_model) < 99, r.Where(c, key + ".distortion_model"),
                   "unknown distortion model '", k.distortion_model, "' (known: radtan, equidistant, none)");
      if (DistortionCount(k.distortion_model) > 0 || c["distortion_coeffs"])
        k.distortion = ReadList(r, c, key, "distortion_coeffs", DistortionCount(k.distortion_model));
      const auto res = ReadList(r, c, key, "resolution", 2);
      // Checked as numbers before they become ints (a huge value does not fit one).
      for (double v : res)
        HOVS_REQUIRE(v >= 1 && v <= 65535 && v == std::floor(v), r.Where(c, key + ".resolution"),
                     "expected [width, height] in 1..65535 pixels");
      k.width = static_cast<int>(res[0]), k.height = static_cast<int>(res[1]);
      if (c["rostopic"]) k.rostopic = r.String(c["rostopic"], key + ".rostopic");
      if (c["T_cn_cnm1"]) {
        const YAML::Node t = c["T_cn_cnm1"];
        HOVS_REQUIRE(t.IsSequence() && t.size() == 4, r.Where(t, key + ".T_cn_cnm1"), "expected 4 rows of 4");
        Eigen::Matrix4d M;
        for (int row = 0; row < 4; ++row) {
          HOVS_REQUIRE(t[row].IsSequence() && t[row].size() == 4, r.Where(t[row], key + ".T_cn_cnm1"),
                       "expected 4 rows of 4");
          for (int col = 0; col < 4; ++col) M(row, col) = r.Number(t[row][col], key + ".T_cn_cnm1");
        }
        k.T_cn_cnm1 = M;
      }
      out.push_back(k);
    }
    return out;
  });
}

UnifiedModel<double> UnifiedFromKalibr(const KalibrCamera& c, const std::string& where) {
  HOVS_REQUIRE(c.camera_model == "omni" && (c.distortion_model == "radtan" || c.distortion_model == "none"), where,
               "hovs reads Kalibr's omni model with radtan or no distortion (this camera is ", c.camera_model, " + ",
               c.distortion_model, ")");
  UnifiedModel<double> m;
  m.width = c.width, m.height = c.height;
  m.xi = c.intrinsics[0], m.fx = c.intrinsics[1], m.fy = c.intrinsics[2], m.cx = c.intrinsics[3],
  m.cy = c.intrinsics[4];
  if (c.distortion.size() == 4) m.distortion = {c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3]};
  m.Check(where);
  return m;
}

void CheckMeiCameraName(const std::string& name, const std::string& where) {
  const bool plain = !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-' || c == '.';
  });
  std::string shown;
  for (unsigned char c : name) shown += c == '\n' ? std::string("\\n") : c < 32 ? std::string("?") : std::string(1, c);
  HOVS_REQUIRE(plain, where, "'", shown,
               "' is not a usable camera name (1 to 64 letters, digits, '_', '-' or '.'; it is written into YAML)");
}

std::string FormatMeiYaml(const UnifiedModel<double>& m, const std::string& name) {
  HOVS_REQUIRE(m.skew == 0, "MEI YAML", "the MEI model has no skew (the model's is ", m.skew, ")");
  CheckMeiCameraName(name, "camera_name");
  const auto num = [](double v) { return FormatNumber("%.17g", v); };
  return "%YAML:1.0\n---\nmodel_type: MEI\ncamera_name: " + name + "\nimage_width: " + std::to_string(m.width) +
         "\nimage_height: " + std::to_string(m.height) + "\nmirror_parameters:\n   xi: " + num(m.xi) +
         "\ndistortion_parameters:\n   k1: " + num(m.distortion.k1) + "\n   k2: " + num(m.distortion.k2) +
         "\n   p1: " + num(m.distortion.p1) + "\n   p2: " + num(m.distortion.p2) +
         "\nprojection_parameters:\n   gamma1: " + num(m.fx) + "\n   gamma2: " + num(m.fy) + "\n   u0: " + num(m.cx) +
         "\n   v0: " + num(m.cy) + "\n";
}

bool LooksLikeMeiYaml(const std::string& text) { return text.find("model_type: MEI") != std::string::npos; }

UnifiedModel<double> ParseMeiYaml(const std::string& text, const std::string& source) {
  return WithYamlErrors(source, [&] {
    const YamlReader r(source);
    // OpenCV's "%YAML:1.0" directive is not YAML 1.2: the line is kept blank so that line numbers hold.
    std::string body = text;
    if (body.rfind("%YAML", 0) == 0) body = body.substr(std::min(body.size(), body.find('\n')));
    const YAML::Node root = r.Load(body);
    HOVS_REQUIRE(root.IsMap(), source, "expected a mapping");
    r.OnlyKeys(root, "",
               {"model_type", "camera_name", "image_width", "image_height", "mirror_parameters",
                "distortion_parameters", "projection_parameters"});
    YAML::Node n;
    HOVS_REQUIRE(r.String(r.Require(root, "", "model_type", &n), "model_type") == "MEI", r.Where(n, "model_type"),
                 "expected MEI");
    UnifiedModel<double> m;
    m.width = r.Integer(r.Require(root, "", "image_width", &n), "image_width");
    m.height = r.Integer(r.Require(root, "", "image_height", &n), "image_height");
    const auto group = [&](const std::string& key, const std::vector<std::string>& names) {
      YAML::Node g;
      r.Require(root, "", key, &g);
      HOVS_REQUIRE(g.IsMap(), r.Where(g, key), "expected a mapping");
      r.OnlyKeys(g, key, std::set<std::string>(names.begin(), names.end()));
      std::vector<double> v;
      for (const auto& name : names) {
        YAML::Node x;
        v.push_back(r.Number(r.Require(g, key, name, &x), key + "." + name));
      }
      return v;
    };
    m.xi = group("mirror_parameters", {"xi"})[0];
    const auto d = group("distortion_parameters", {"k1", "k2", "p1", "p2"});
    m.distortion = {d[0], d[1], d[2], d[3]};
    const auto p = group("projection_parameters", {"gamma1", "gamma2", "u0", "v0"});
    m.fx = p[0], m.fy = p[1], m.cx = p[2], m.cy = p[3];
    m.Check(source);
    return m;
  });
}

}  // namespace hovs::calib
