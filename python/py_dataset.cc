// hovs.Dataset: a dataset manifest (core/manifest.h), its images, ground-truth EXR channels and board corners as
// NumPy arrays.
#include <pybind11/stl.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/model_files.h"
#include "core/io.h"
#include "core/manifest.h"
#include "io/image_io.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "scenes/ground_truth.h"

namespace hovs::python {

namespace {

namespace fs = std::filesystem;

// An EXR's channels; `image`, when given, is the file whose size the ground truth must have (as the CLI checks).
py::dict ReadExrFile(const std::string& path, const fs::path& image = {}) {
  const io::ExrChannels ch = [&] {
    py::gil_scoped_release release;
    return io::ReadExr(path);
  }();
  if (!image.empty()) {
    const io::ImageHeader h = io::ReadImageHeader(image);
    HOVS_REQUIRE(ch.width == h.width && ch.height == h.height, path, "the ground truth is ", ch.width, " x ", ch.height,
                 " but its image ", image.string(), " is ", h.width, " x ", h.height);
  }
  py::dict d;
  for (const auto& [name, values] : ch.channels) d[py::str(name)] = NewFloatImage(ch.width, ch.height, values.data());
  return d;
}

class Dataset {
 public:
  explicit Dataset(const std::string& path) : path_(path), manifest_(LoadDatasetManifest(path)) {}

  std::vector<std::string> Units() const {
    std::vector<std::string> names;
    for (const auto& u : manifest_["units"]) names.push_back(u["name"].get<std::string>());
    return names;
  }
  std::vector<int64_t> Frames() const {
    std::vector<int64_t> ids;
    for (const auto& f : manifest_["frames"]) ids.push_back(f["id"].get<int64_t>());
    return ids;
  }

  // The view of `unit` (default: the first unit) in frame `id`, or an error naming the frame and unit.
  const nlohmann::json& View(int64_t id, const std::string& unit) const {
    const std::string u = unit.empty() ? Units().at(0) : unit;
    for (const auto& f : manifest_["frames"]) {
      if (f["id"].get<int64_t>() != id) continue;
      for (const auto& v : f["views"])
        if (v["unit"].get<std::string>() == u) return v;
      throw Error(path_.string(), "frame " + std::to_string(id) + " has no view of unit '" + u + "'");
    }
    throw Error(path_.string(), "no frame " + std::to_string(id));
  }

  py::array Image(int64_t id, const std::string& unit, bool as_float) const {
    const fs::path image = ManifestPath(path_, View(id, unit)["image"]);
    if (!as_float) {
      const io::Image8Bits im = [&] {
        py::gil_scoped_release release;
        return io::ReadImage8(image);
      }();
      return NewImage(im.width, im.height, im.channels, im.data.data());
    }
    int w = 0, h = 0, c = 0;
    const io::PixelBuffer px = [&] {
      py::gil_scoped_release release;
      return io::ReadImage(image, &w, &h, &c);
    }();
    py::array_t<float> a = c == 1 ? py::array_t<float>({py::ssize_t(h), py::ssize_t(w)})
                                  : py::array_t<float>({py::ssize_t(h), py::ssize_t(w), py::ssize_t(c)});
    std::copy(px.begin(), px.end(), a.mutable_data());
    return std::move(a);
  }

  const nlohmann::json& Truth(int64_t id, const std::string& unit) const {
    const auto& v = View(id, unit);
    HOVS_REQUIRE(v.contains("ground_truth"), path_.string(), "frame ", id, " has no ground truth (a real capture?)");
    return v["ground_truth"];
  }

  py::dict GroundTruth(int64_t id, const std::string& unit) const {
    const auto& truth = Truth(id, unit);
    HOVS_REQUIRE(truth.contains("exr"), path_.string(), "frame ", id, " has no ground-truth image (written with ",
                 "--truth none)");
    return ReadExrFile(ManifestPath(path_, truth["exr"]).string(), ManifestPath(path_, View(id, unit)["image"]));
  }

  py::dict Corners(int64_t id, const std::string& unit) const {
    const fs::path sidecar = ManifestPath(path_, Truth(id, unit)["sidecar"]);
    const auto corners = scenes::VisibleSidecarCorners(sidecar);
    const py::ssize_t n = py::ssize_t(corners.size());
    py::array_t<int32_t> ids({n});
    py::array_t<double> board({n, py::ssize_t(2)}), pixels({n, py::ssize_t(2)});
    py::array_t<double> world({n, py::ssize_t(3)}), mirror({n, py::ssize_t(3)});
    for (py::ssize_t i = 0; i < n; ++i) {
      const auto& c = corners[i];
      ids.mutable_data()[i] = c.id;
      for (int k = 0; k < 2; ++k) board.mutable_data()[2 * i + k] = c.board_xy(k);
      for (int k = 0; k < 2; ++k) pixels.mutable_data()[2 * i + k] = c.pixel(k);
      for (int k = 0; k < 3; ++k) world.mutable_data()[3 * i + k] = c.world(k);
      for (int k = 0; k < 3; ++k) mirror.mutable_data()[3 * i + k] = c.mirror_point(k);
    }
    py::dict d;
    d["ids"] = ids, d["board_xy"] = board, d["pixels"] = pixels, d["world"] = world, d["mirror_points"] = mirror;
    return d;
  }

  py::array_t<double> WorldFromMirror(const std::string& unit) const {
    const auto names = Units();
    const std::string u = unit.empty() ? names.at(0) : unit;
    for (size_t i = 0; i < names.size(); ++i) {
      if (names[i] != u) continue;
      const auto rig = scenes::UnitFromJson(manifest_["units"][i], path_.string() + " (units)");
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R = rig.world_from_mirror.rotation.toRotationMatrix();
      return MatrixFromRotationTranslation(R.data(), rig.world_from_mirror.translation.data());
    }
    throw Error(path_.string(), "no unit named '" + u + "'");
  }

  Camera Rig(const std::string& unit, double scene_distance) const {
    return {apps::LoadModelSpec(path_.string(), unit, scene_distance), path_.string()};
  }

  std::string ManifestText() const { return manifest_.dump(); }
  std::string path() const { return path_.string(); }

 private:
  fs::path path_;
  nlohmann::json manifest_;
};

}  // namespace

void BindDataset(py::module_& m) {
  m.def(
      "read_exr", [](const std::string& path) { return ReadExrFile(path); }, py::arg("path"),
      "An OpenEXR file's channels by name, each float32 (H, W) (ground truth, range exports).");
  py::class_<Dataset>(m, "Dataset", "A hovs dataset (its dataset.json manifest): rendered sets and real captures.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def_property_readonly("path", &Dataset::path)
      .def_property_readonly("units", &Dataset::Units, "The units' names, in the manifest's order.")
      .def_property_readonly("frames", &Dataset::Frames, "The frames' ids.")
      .def_property_readonly(
          "manifest", [](const Dataset& d) { return py::module_::import("json").attr("loads")(d.ManifestText()); })
      .def("image", &Dataset::Image, py::arg("frame"), py::arg("unit") = "", py::arg("as_float") = false,
           "The view's image: uint8 (H, W) or (H, W, 3); as_float: float32 in [0, 1] with every channel as stored.")
      .def("ground_truth", &Dataset::GroundTruth, py::arg("frame"), py::arg("unit") = "",
           "The ground-truth EXR's channels by name, each float32 (H, W) (see the manifest's documentation).")
      .def("corners", &Dataset::Corners, py::arg("frame"), py::arg("unit") = "",
           "The first board's visible corners: ids (K,), board_xy (K, 2) and world (K, 3) in metres, exact pixels "
           "(K, 2), and mirror_points (K, 3), where each corner's ray reflects (the unit's mirror frame).")
      .def("world_from_mirror", &Dataset::WorldFromMirror, py::arg("unit") = "",
           "The unit's pose: a 4 x 4 transform from its mirror frame to the world.")
      .def("camera", &Dataset::Rig, py::arg("unit") = "", py::arg("scene_distance") = 10.0,
           "The exact model of a unit's rig.");
}

}  // namespace hovs::python
