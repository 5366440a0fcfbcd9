// Design metrics and studies (design/), and sparse stereo triangulation (depth/stereo.h), from Python.
#include <pybind11/stl.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/json.h"
#include "depth/stereo.h"
#include "design/config.h"
#include "design/study.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "scenes/ground_truth.h"

namespace hovs::python {

namespace {

// A JSON value as the Python object json.loads makes of it.
py::object FromJson(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

design::DesignPoint Point(const design::DesignConfig& cfg, double a, double b, double rim_diameter) {
  design::DesignPoint p{a, b, rim_diameter > 0 ? rim_diameter : cfg.problem.d.min};
  HOVS_REQUIRE(std::isfinite(a) && std::isfinite(b) && a > 0 && b > 0 && p.d > 0, "design point",
               "a, b and the rim diameter must be positive metres (got ", a, ", ", b, ", ", p.d, ")");
  return p;
}

py::object DesignMetrics(const std::string& config, double a, double b, double rim_diameter) {
  const design::DesignConfig cfg = design::LoadDesignConfig(config);
  return FromJson(design::OptimumJson(design::EvaluateDesign(Point(cfg, a, b, rim_diameter), cfg.problem, "given")));
}

py::array_t<double> Resolution(const std::string& config, double a, double b, double rim_diameter, int n) {
  HOVS_REQUIRE(n >= 2 && n <= 1000000, "n", "must be 2..1000000 (got ", n, ")");
  const design::DesignConfig cfg = design::LoadDesignConfig(config);
  const auto s = design::RadialResolution(Point(cfg, a, b, rim_diameter), cfg.problem.camera, n);
  py::array_t<double> out({py::ssize_t(s.size()), py::ssize_t(3)});
  for (size_t i = 0; i < s.size(); ++i) {
    out.mutable_data()[3 * i] = s[i].elevation_deg;
    out.mutable_data()[3 * i + 1] = s[i].rho_px;
    out.mutable_data()[3 * i + 2] = s[i].px_per_deg;
  }
  return out;
}

py::object DesignStudy(const std::string& config) {
  const design::DesignConfig cfg = design::LoadDesignConfig(config);
  const design::DesignStudy s = [&] {
    py::gil_scoped_release release;
    return design::RunDesignStudy(cfg);
  }();
  return FromJson(design::DesignStudyJson(cfg, s));
}

// right_from_left: a 4 x 4 rigid transform, or a `hovs stereo-calibrate` result (its right_from_left).
Rigid3d RightFromLeft(const py::handle& pose) {
  if (py::isinstance<py::str>(pose)) {
    const std::string path = pose.cast<std::string>();
    const auto j = ReadJsonFile(path);
    HOVS_REQUIRE(j.is_object() && j.contains("right_from_left"), path,
                 "not a hovs stereo-calibrate result (no right_from_left)");
    return scenes::PoseFromJson(j["right_from_left"], path + " (right_from_left)");
  }
  const Rows r = AsRows(pose, 4, "right_from_left");
  HOVS_REQUIRE(!r.single && r.n == 4, "right_from_left", "expected a 4 x 4 matrix");
  const double* p = r.data();
  for (int k = 0; k < 16; ++k)
    HOVS_REQUIRE(std::isfinite(p[k]), "right_from_left", "entry (", k / 4, ", ", k % 4, ") is not a finite number");
  Eigen::Matrix3d R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = p[4 * i + j];
  HOVS_REQUIRE((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6 && R.determinant() > 0 && p[12] == 0 &&
                   p[13] == 0 && p[14] == 0 && p[15] == 1,
               "right_from_left", "not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)");
  return Rigid3d(Eigen::Quaterniond(R), Vec3d(p[3], p[7], p[11]));
}

py::dict Triangulate(const py::handle& bearings_left, const py::handle& bearings_right, const py::handle& pose,
                     double sigma_deg) {
  HOVS_REQUIRE(std::isfinite(sigma_deg) && sigma_deg >= 0, "sigma_deg", "must be >= 0 (got ", sigma_deg, ")");
  const Rows l = AsRows(bearings_left, 3, "bearings_left"), r = AsRows(bearings_right, 3, "bearings_right");
  HOVS_REQUIRE(l.n == r.n && l.single == r.single, "bearings_right", "has ", r.n, " rows; bearings_left has ", l.n);
  depth::StereoRig rig;
  rig.right_from_left = RightFromLeft(pose);
  py::array_t<double> points = NewRows(l.n, 3, l.single);
  py::array_t<double> range = NewRows(l.n, 1, l.single), sigma = NewRows(l.n, 1, l.single);
  py::array_t<double> gap = NewRows(l.n, 1, l.single);
  py::array_t<bool> ok = NewFlags(l.n, l.single);
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < l.n; ++i) {
      const Vec3d bl(l.data() + 3 * i), br(r.data() + 3 * i);
      if (!bl.allFinite() || !br.allFinite()) continue;
      const auto t = depth::Triangulate(rig, bl, br, sigma_deg * M_PI / 180);
      if (!t.ok) continue;
      for (int k = 0; k < 3; ++k) points.mutable_data()[3 * i + k] = t.point_left(k);
      range.mutable_data()[i] = t.range_left, sigma.mutable_data()[i] = t.sigma_range;
      gap.mutable_data()[i] = t.gap, ok.mutable_data()[i] = true;
    }
  }
  const auto flat = [&](py::array_t<double> a) { return l.single ? a : a.reshape({l.n}); };
  py::dict d;
  d["points"] = points, d["range"] = flat(range), d["sigma_range"] = flat(sigma), d["gap"] = flat(gap);
  d["valid"] = ok;
  return d;
}

void WritePointCloud(const std::string& path, const py::handle& points, const py::handle& colors) {
  const Rows p = AsRows(points, 3, "points");
  std::vector<depth::ColouredPoint> cloud(p.n);
  for (py::ssize_t i = 0; i < p.n; ++i) {
    cloud[i].p = Vec3d(p.data() + 3 * i);
    HOVS_REQUIRE(cloud[i].p.allFinite(), "points", "row ", i, " is not finite");
  }
  if (!colors.is_none()) {
    const py::array a = py::array::ensure(colors);
    if (!a || a.dtype().kind() != 'u' || a.dtype().itemsize() != 1)
      throw py::type_error("colors: expected a uint8 array of shape (N, 3)");
    HOVS_REQUIRE(a.ndim() == 2 && a.shape(1) == 3, "colors", "expected shape (N, 3)");
    HOVS_REQUIRE(a.shape(0) == p.n, "colors", "has ", a.shape(0), " rows; points has ", p.n);
    const auto c = py::array_t<uint8_t, py::array::c_style>::ensure(a);
    for (py::ssize_t i = 0; i < p.n; ++i)
      for (int k = 0; k < 3; ++k) cloud[i].rgb[k] = c.data()[3 * i + k];
  }
  const std::string ext = std::filesystem::path(path).extension().string();
  HOVS_REQUIRE(ext == ".ply" || ext == ".vtp", path, "expected a .ply or .vtp file name");
  py::gil_scoped_release release;
  if (ext == ".ply")
    depth::WritePly(path, cloud);
  else
    depth::WriteVtp(path, cloud);
}

}  // namespace

void BindStudy(py::module_& m) {
  m.def("design_metrics", &DesignMetrics, py::arg("config"), py::arg("a"), py::arg("b"), py::arg("rim_diameter") = 0.0,
        "The metrics and constraints of one hyperboloid (a, b, rim diameter in metres; 0: the config's) for the "
        "camera and constraints of a design config (YAML), with the keys of design.json's designs.");
  m.def("radial_resolution", &Resolution, py::arg("config"), py::arg("a"), py::arg("b"), py::arg("rim_diameter") = 0.0,
        py::arg("n") = 200,
        "(n, 3): elevation (deg), image radius (px), radial resolution (px/deg) over the design's field.");
  m.def("design_study", &DesignStudy, py::arg("config"),
        "The design study of a config (sweep, continuous and integer-millimetre optima, the marked design): "
        "design.json's content.");
  m.def("write_point_cloud", &WritePointCloud, py::arg("path"), py::arg("points"), py::arg("colors") = py::none(),
        "Writes points (N, 3) and optional uint8 colors (N, 3) as hovs' depth command does: ASCII PLY (every "
        "float exactly) or VTK PolyData (.vtp), atomically.");
  m.def("triangulate", &Triangulate, py::arg("bearings_left"), py::arg("bearings_right"), py::arg("right_from_left"),
        py::arg("sigma_deg") = 0.01,
        "Intersects pairs of bearings (each unit's mirror frame, (N, 3)). right_from_left: a 4 x 4 rigid transform "
        "or a stereo.json path. Returns points (N, 3) in the left mirror frame, range, sigma_range (m, from an "
        "angular noise sigma_deg), gap (m, between the rays) and valid.");
}

}  // namespace hovs::python
