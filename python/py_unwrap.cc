// hovs.Unwrapper: a layout's virtual views built from a camera model (unwrap/remap_table.h) and the fast remap
// (unwrap/remap.h) applied to NumPy images, or a mapping file written by `hovs unwrap --save-map` loaded as it is.
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "unwrap/layout.h"
#include "unwrap/remap.h"

namespace hovs::python {

namespace {

class Unwrapper {
 public:
  explicit Unwrapper(unwrap::RemapTable table)
      : table_(std::make_unique<unwrap::RemapTable>(std::move(table))), remapper_(*table_) {}

  static std::unique_ptr<Unwrapper> Build(const Camera& camera, const std::string& layout,
                                          const std::string& interpolation, int tile, double max_interp_error) {
    unwrap::RemapOptions options;
    options.tile = tile, options.max_interp_error = max_interp_error;
    options.Check("Unwrapper options");
    const unwrap::Layout l = unwrap::ResolveLayout(layout, &camera.model);
    auto u = [&] {
      py::gil_scoped_release release;
      nlohmann::json versions(apps::Versions());
      return std::make_unique<Unwrapper>(unwrap::BuildRemapTable(camera.model, l, options, versions.dump()));
    }();
    u->interpolation_ = unwrap::ParseInterpolation(interpolation);
    return u;
  }
  static std::unique_ptr<Unwrapper> Load(const std::string& path, const std::string& interpolation) {
    auto u = std::make_unique<Unwrapper>(unwrap::LoadRemapTable(path));
    u->interpolation_ = unwrap::ParseInterpolation(interpolation);
    return u;
  }

  void Save(const std::string& path) const { unwrap::SaveRemapTable(path, *table_); }

  int ViewIndex(const py::handle& view) const {
    const int n = int(table_->views.size());
    if (py::isinstance<py::str>(view)) {
      const std::string name = view.cast<std::string>();
      for (int i = 0; i < n; ++i)
        if (table_->views[i].spec.name == name) return i;
      throw Error("view", "no view named '" + name + "' in this layout");
    }
    if (!py::isinstance<py::int_>(view)) throw py::type_error("view: expected a view's name or index");
    const long i = view.cast<long>();
    HOVS_REQUIRE(i >= -n && i < n, "view", "index ", i, " out of range (", n, " views)");
    return int(i < 0 ? i + n : i);
  }

  py::list Views() const {
    py::list out;
    for (const auto& v : table_->views) {
      py::dict d;
      d["name"] = v.spec.name, d["type"] = ToString(v.spec.type);
      d["width"] = v.spec.width, d["height"] = v.spec.height, d["valid_pixels"] = v.valid_pixels;
      out.append(d);
    }
    return out;
  }

  py::tuple Maps(const py::handle& view) const {
    const int i = ViewIndex(view);
    const auto& spec = table_->views[i].spec;
    std::vector<float> mx, my;
    {
      py::gil_scoped_release release;
      table_->DecodeView(i, &mx, &my);
    }
    return py::make_tuple(NewFloatImage(spec.width, spec.height, mx.data()),
                          NewFloatImage(spec.width, spec.height, my.data()));
  }

  py::list Remap(const py::handle& image, const std::string& format) {
    const Image im = AsImage(image, "image");
    unwrap::PixelFormat f = im.channels == 1 ? unwrap::PixelFormat::kGray8 : unwrap::PixelFormat::kRgb8;
    if (!format.empty()) {
      f = unwrap::ParsePixelFormat(format);
      const int expected = f == unwrap::PixelFormat::kRgb8 ? 3 : 1;
      HOVS_REQUIRE(im.channels == expected, "image", "format ", format, " needs ", expected,
                   " channel(s), the image has ", im.channels);
    }
    HOVS_REQUIRE(im.width == table_->source_width && im.height == table_->source_height, "image", "is ", im.width,
                 " x ", im.height, "; the views were built for ", table_->source_width, " x ", table_->source_height);
    const unwrap::ImageView src{im.array.data(), im.width, im.height, size_t(im.width) * im.channels, f};
    std::vector<unwrap::Image8> outs;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);  // the remapper's pyramid is per call
      remapper_.Run(src, interpolation_, &outs);
    }
    py::list out;
    for (const auto& o : outs) out.append(NewImage(o.width, o.height, o.channels, o.data.data()));
    return out;
  }

  const unwrap::RemapTable& table() const { return *table_; }

 private:
  std::unique_ptr<unwrap::RemapTable> table_;
  unwrap::Remapper remapper_;
  unwrap::Interpolation interpolation_ = unwrap::Interpolation::kBilinear;
  std::mutex mutex_;
};

}  // namespace

void BindUnwrap(py::module_& m) {
  py::class_<Unwrapper>(m, "Unwrapper",
                        "The virtual views of a layout (perspective views, panoramas) as remap tables, and the "
                        "remap of 8-bit frames (grey, RGB or raw RGGB Bayer) into them.")
      .def(py::init(&Unwrapper::Build), py::arg("camera"), py::arg("layout") = "article",
           py::arg("interpolation") = "bilinear", py::arg("tile") = 0, py::arg("max_interp_error") = 1.0 / 64,
           "Builds the tables of a layout (a preset: article, panorama, longlat; or a layout YAML file) for the "
           "camera. interpolation: nearest, bilinear or bicubic.")
      .def_static("load", &Unwrapper::Load, py::arg("path"), py::arg("interpolation") = "bilinear",
                  "A mapping file written by `hovs unwrap --save-map` or Unwrapper.save.")
      .def("save", &Unwrapper::Save, py::arg("path"), "Writes the mapping file (atomically).")
      .def_property_readonly("views", &Unwrapper::Views)
      .def_property_readonly(
          "source_size",
          [](const Unwrapper& u) { return py::make_tuple(u.table().source_width, u.table().source_height); })
      .def_property_readonly("header", [](const Unwrapper& u) { return u.table().header; })
      .def("maps", &Unwrapper::Maps, py::arg("view"),
           "(map_x, map_y) float32 (H, W) source coordinates of a view (name or index) as the table encodes them, "
           "-1 where invalid: cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR) samples the same positions.")
      .def("remap", &Unwrapper::Remap, py::arg("image"), py::arg("format") = "",
           "Every view of a frame: uint8 (H, W) grey or (H, W, 3) RGB; format 'bayer_rggb' reads an (H, W) raw "
           "mosaic and gives RGB views. Returns a list of arrays, one per view.");
}

}  // namespace hovs::python
