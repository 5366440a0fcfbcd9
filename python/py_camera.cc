// hovs.Camera: projection and back-projection of N points at once, through the core's models (any_model.h).
#include <ceres/jet.h>
#include <pybind11/stl.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <filesystem>
#include <limits>
#include <optional>
#include <utility>

#include "apps/model_files.h"
#include "core/io.h"
#include "python/arrays.h"
#include "python/bindings.h"

namespace hovs::python {

namespace {

// Runs body(i) for i in [0, n) on TBB's threads without the GIL, in blocks large enough that the scheduling
// cost stays below the per-point work of the cheapest model (the unified one, ~20 ns).
template <class Body>
void ParallelRows(py::ssize_t n, const Body& body) {
  py::gil_scoped_release release;
  tbb::parallel_for(tbb::blocked_range<py::ssize_t>(0, n, 16384), [&](const tbb::blocked_range<py::ssize_t>& r) {
    for (py::ssize_t i = r.begin(); i != r.end(); ++i) body(i);
  });
}

// The same with body(begin, end) on each block.
template <class Body>
void ParallelBlocks(py::ssize_t n, const Body& body) {
  py::gil_scoped_release release;
  tbb::parallel_for(tbb::blocked_range<py::ssize_t>(0, n, 16384),
                    [&](const tbb::blocked_range<py::ssize_t>& r) { body(r.begin(), r.end()); });
}

py::tuple Project(const Camera& c, const py::handle& points, bool bounded) {
  const Rows in = AsRows(points, 3, "points");
  py::array_t<double> uv = NewRows(in.n, 2, in.single, /*fill=*/false);
  py::array_t<bool> valid = NewFlags(in.n, in.single, /*fill=*/false);
  const double* p = in.data();
  double* out = uv.mutable_data();
  bool* ok = valid.mutable_data();
  const AnyModel& model = c.model;
  const auto finish = [&](py::ssize_t i) {  // a point that is not finite or at the origin has no pixel
    const Vec3d X(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    if (!(X.allFinite() && X.squaredNorm() > 0)) ok[i] = false;
    if (!ok[i]) out[2 * i] = out[2 * i + 1] = std::numeric_limits<double>::quiet_NaN();
  };
  if (bounded) {  // in blocks: the polynomial model projects a block's points together
    ParallelBlocks(in.n, [&](py::ssize_t begin, py::ssize_t end) {
      model.ImgFromMirrorBatch(p + 3 * begin, static_cast<std::size_t>(end - begin), out + 2 * begin, ok + begin);
      for (py::ssize_t i = begin; i != end; ++i) finish(i);
    });
  } else {
    ParallelRows(in.n, [&](py::ssize_t i) {
      Vec2d q(0, 0);
      ok[i] = model.ImgFromPointUnbounded(Vec3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]), &q);
      out[2 * i] = q(0), out[2 * i + 1] = q(1);
      finish(i);
    });
  }
  return py::make_tuple(uv, valid);
}

py::tuple Unproject(const Camera& c, const py::handle& pixels) {
  const Rows in = AsRows(pixels, 2, "pixels");
  py::array_t<double> rays = NewRows(in.n, 3, in.single, /*fill=*/false);
  py::array_t<bool> valid = NewFlags(in.n, in.single, /*fill=*/false);
  const double* p = in.data();
  double* out = rays.mutable_data();
  bool* ok = valid.mutable_data();
  const AnyModel& model = c.model;
  ParallelRows(in.n, [&](py::ssize_t i) {
    const Vec2d uv(p[2 * i], p[2 * i + 1]);
    Vec3d b;
    const bool good = uv.allFinite() && model.MirrorFromImg(uv, &b);
    if (!good) b.setConstant(std::numeric_limits<double>::quiet_NaN());
    out[3 * i] = b(0), out[3 * i + 1] = b(1), out[3 * i + 2] = b(2), ok[i] = good;
  });
  return py::make_tuple(rays, valid);
}

// d(u, v) / d(X): the core's templated projection differentiated by Ceres' jets (polynomial and unified models,
// the formula without the validity domain, as the calibration's solver sees it).
template <class Model>
bool JetJacobian(const Model& model, const Vec3d& X, Vec2d* uv, double* J) {
  using Jet = ceres::Jet<double, 3>;
  Vec3<Jet> Xj;
  for (int k = 0; k < 3; ++k) Xj(k) = Jet(X(k), k);
  Vec2<Jet> q;
  if (!model.ImgFromCam(Xj, &q)) return false;
  for (int r = 0; r < 2; ++r) {
    (*uv)(r) = q(r).a;
    for (int k = 0; k < 3; ++k) J[3 * r + k] = q(r).v(k);
  }
  return true;
}

py::tuple ProjectJacobian(const Camera& c, const py::handle& points) {
  const AnyModel& model = c.model;
  HOVS_REQUIRE(model.kind() != AnyModel::Kind::kExact, c.source,
               "project_jacobian needs a polynomial or unified model (the exact model's projection is a solve)");
  const Rows in = AsRows(points, 3, "points");
  py::array_t<double> jac =
      in.single ? py::array_t<double>({2, 3}) : py::array_t<double>({in.n, py::ssize_t(2), py::ssize_t(3)});
  std::fill_n(jac.mutable_data(), jac.size(), std::numeric_limits<double>::quiet_NaN());
  py::array_t<double> uv = NewRows(in.n, 2, in.single);
  py::array_t<bool> valid = NewFlags(in.n, in.single);
  const double* p = in.data();
  double *J = jac.mutable_data(), *out = uv.mutable_data();
  bool* ok = valid.mutable_data();
  const auto poly = model.polynomial().Cast<ceres::Jet<double, 3>>();
  const auto unified = model.unified().Cast<ceres::Jet<double, 3>>();
  ParallelRows(in.n, [&](py::ssize_t i) {
    const Vec3d X(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    Vec2d q;
    if (!X.allFinite() || X.squaredNorm() == 0) return;
    const bool good = model.kind() == AnyModel::Kind::kPolynomial ? JetJacobian(poly, X, &q, J + 6 * i)
                                                                  : JetJacobian(unified, X, &q, J + 6 * i);
    if (!good) return;
    out[2 * i] = q(0), out[2 * i + 1] = q(1), ok[i] = true;
  });
  return py::make_tuple(jac, uv, valid);
}

py::dict Parameters(const Camera& c) {
  py::dict d;
  const AnyModel& m = c.model;
  switch (m.kind()) {
    case AnyModel::Kind::kPolynomial: {
      const auto& p = m.polynomial();
      d["cx"] = p.cx, d["cy"] = p.cy, d["c"] = p.c, d["d"] = p.d, d["e"] = p.e;
      d["poly"] = p.poly, d["p1"] = p.p1, d["p2"] = p.p2, d["inv_poly"] = p.inv_poly, d["rho_min"] = p.rho_min,
      d["rho_max"] = p.rho_max;
      d["inverse_error_px"] = p.inv_error_px;
      break;
    }
    case AnyModel::Kind::kUnified: {
      const auto& u = m.unified();
      d["xi"] = u.xi, d["fx"] = u.fx, d["fy"] = u.fy, d["cx"] = u.cx, d["cy"] = u.cy, d["skew"] = u.skew;
      d["k1"] = u.distortion.k1, d["k2"] = u.distortion.k2, d["p1"] = u.distortion.p1, d["p2"] = u.distortion.p2;
      d["annulus_px"] = py::make_tuple(m.annulus().first, m.annulus().second);
      break;
    }
    case AnyModel::Kind::kExact: {
      const auto& r = m.exact();
      d["mirror_a"] = r.mirror.a, d["mirror_b"] = r.mirror.b, d["mirror_c"] = r.mirror.c();
      d["rim_diameter"] = r.mirror.rim_diameter, d["occluder_radius"] = r.occluder_radius;
      d["fx"] = r.camera.fx, d["fy"] = r.camera.fy, d["cx"] = r.camera.cx, d["cy"] = r.camera.cy;
      d["k1"] = r.camera.distortion.k1, d["k2"] = r.camera.distortion.k2;
      d["p1"] = r.camera.distortion.p1, d["p2"] = r.camera.distortion.p2;
      const Eigen::Matrix3d R = r.cam_from_mirror.rotation.toRotationMatrix();
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> Rr = R;
      d["cam_from_mirror"] = MatrixFromRotationTranslation(Rr.data(), r.cam_from_mirror.translation.data());
      d["single_viewpoint"] = r.IsSingleViewpoint();
      d["scene_distance"] = m.scene_distance();
      break;
    }
  }
  return d;
}

Camera LoadCamera(const std::string& path, const std::string& unit, const std::string& model, double scene_distance,
                  const std::optional<std::pair<int, int>>& image_size) {
  RequireFile(path, "model file");
  HOVS_REQUIRE(model == "auto" || model == "physical" || model == "polynomial" || model == "unified", "model",
               "expected auto, physical, polynomial or unified (got '", model, "')");
  apps::ImageSize size;
  if (image_size) {
    size.width = image_size->first, size.height = image_size->second;
    HOVS_REQUIRE(size.width > 0 && size.height > 0 && size.width <= 65535 && size.height <= 65535, "image_size",
                 "expected (width, height) of 1..65535 pixels each");
  }
  if (model != "auto") return {apps::LoadCalibratedModel(path, model, scene_distance, size), path};
  return {apps::LoadModelSpec(path, unit, scene_distance, size), path};
}

}  // namespace

void BindCamera(py::module_& m) {
  py::class_<Camera>(m, "Camera",
                     "A catadioptric camera model: exact (mirror + pinhole + pose), polynomial (OCam) or unified "
                     "(Mei). Points and bearings are in the mirror frame (metres, origin at the viewpoint F1, z "
                     "towards the mirror); pixels are (column, row) with the top-left pixel's centre at (0, 0).")
      .def_property_readonly("kind", [](const Camera& c) { return std::string(c.model.KindName()); })
      .def_property_readonly("width", [](const Camera& c) { return c.model.width(); })
      .def_property_readonly("height", [](const Camera& c) { return c.model.height(); })
      .def_property_readonly("source", [](const Camera& c) { return c.source; })
      .def_property_readonly("parameters", &Parameters)
      .def("project", &Project, py::arg("points"), py::arg("bounded") = true,
           "points (N, 3) -> (pixels (N, 2), valid (N,)). bounded: only the model's valid domain (the calibrated "
           "annulus, the mirror inside its rim, the image); False: the formula wherever it has a value. Invalid "
           "rows are NaN.")
      .def("unproject", &Unproject, py::arg("pixels"),
           "pixels (N, 2) -> (unit bearings (N, 3), valid (N,)); NaN outside the model's valid domain.")
      .def("project_jacobian", &ProjectJacobian, py::arg("points"),
           "points (N, 3) -> (d(u, v)/d(x, y, z) (N, 2, 3), pixels (N, 2), valid (N,)); polynomial and unified "
           "models.")
      .def("__repr__", [](const Camera& c) {
        return "<hovs.Camera " + std::string(c.model.KindName()) + " " + std::to_string(c.model.width()) + "x" +
               std::to_string(c.model.height()) + " from " + c.source + ">";
      });
  m.def("load_camera", &LoadCamera, py::arg("path"), py::arg("unit") = "", py::arg("model") = "auto",
        py::arg("scene_distance") = 10.0, py::arg("image_size") = py::none(),
        "A camera model from a file: a hovs calibration.json (model: auto, physical, polynomial or unified), "
        "OCamCalib's calib_results.txt, an OpenCV omnidir YAML or XML file (image_size=(width, height) when it has "
        "none, as the omni_calibration sample's), a Kalibr camchain (unit: cam0, cam1, ...), a MEI YAML, a scene "
        "YAML or a dataset manifest (the exact rig of `unit`, default the first).");
}

}  // namespace hovs::python
