#include "unwrap/layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "core/error.h"
#include "core/io.h"
#include "core/large_pages.h"
#include "core/yaml_reader.h"

namespace hovs::unwrap {
namespace {
constexpr double kDeg = M_PI / 180.0;
}

void ViewSpec::Check(const std::string& where) const {
  HOVS_REQUIRE(!name.empty(), where, "a view needs a name");
  HOVS_REQUIRE(name.find_first_of("/\\ ") == std::string::npos, where, "view name '", name,
               "' must not contain spaces or slashes (it names output files)");
  HOVS_REQUIRE(width > 0 && height > 0 && width <= 32768 && height <= 32768, where + " (" + name + ")",
               "size must be 1..32768 pixels (got ", width, " x ", height, ")");
  if (type == ViewProjection::kPerspective) {
    HOVS_REQUIRE(hfov_deg > 0 && hfov_deg < 180, where + " (" + name + ")",
                 "a perspective view needs 0 < hfov < 180 degrees (got ", hfov_deg, ")");
  }
  View().Check(where + " (" + name + ")");
}

VirtualView<double> ViewSpec::View() const {
  if (type == ViewProjection::kPerspective)
    return VirtualView<double>::Perspective(width, height, hfov_deg * kDeg, yaw_deg * kDeg, pitch_deg * kDeg,
                                            roll_deg * kDeg);
  VirtualView<double> v =
      VirtualView<double>::Panorama(type, width, height, elevation_min_deg * kDeg, elevation_max_deg * kDeg,
                                    azimuth_centre_deg * kDeg, azimuth_span_deg * kDeg);
  v.mirror_from_view = pole.normalized();
  return v;
}

void Layout::Check(const std::string& where) const {
  HOVS_REQUIRE(!views.empty() && views.size() <= 256, where, "a layout has 1 to 256 views (got ", views.size(), ")");
  std::set<std::string> names;
  for (const auto& v : views) {
    v.Check(where);
    HOVS_REQUIRE(names.insert(v.name).second, where, "two views are named '", v.name, "'");
  }
}

bool Layout::IsRig() const {
  for (const auto& v : views)
    if (!v.unit.empty()) return true;
  return false;
}

std::vector<std::string> PresetNames() { return {"article", "panorama", "longlat", "binocular"}; }

std::size_t ViewsMemoryBytes(const std::vector<ViewSpec>& views) {
  std::size_t total = 0, largest = 0;
  for (const ViewSpec& v : views) {
    const std::size_t px =
        static_cast<std::size_t>(std::max(v.width, 0)) * static_cast<std::size_t>(std::max(v.height, 0));
    total += px, largest = std::max(largest, px);
  }
  return total * (3 + 8) + largest * 12;
}

void CheckViewsMemory(const std::string& where, const std::vector<ViewSpec>& views,
                      std::optional<std::size_t> available) {
  std::size_t px = 0;
  for (const ViewSpec& v : views) px += static_cast<std::size_t>(v.width) * static_cast<std::size_t>(v.height);
  char what[80];
  std::snprintf(what, sizeof what, "a layout of %zu views, %.1f megapixels in all, at worst", views.size(),
                static_cast<double>(px) * 1e-6);
  RequireMemory(where, what, ViewsMemoryBytes(views), available, "make the views smaller or fewer, or free memory");
}

Layout PresetLayout(const std::string& name) {
  Layout l;
  l.name = name;
  if (name == "article") {
    const char* names[] = {"view0", "view60", "view120", "view180", "view240", "view300"};
    for (int i = 0; i < 6; ++i) {
      ViewSpec v;
      v.name = names[i];
      v.yaw_deg = 60.0 * i;
      l.views.push_back(v);
    }
  } else if (name == "binocular") {
    const int yaws[6] = {120, 180, 240, 300, 0, 60};
    for (int i = 0; i < 6; ++i) {
      ViewSpec v;
      v.unit = i < 3 ? "0" : "1";
      char n[32];
      std::snprintf(n, sizeof n, "unit%d_view%d", i < 3 ? 0 : 1, yaws[i]);
      v.name = n;
      v.yaw_deg = yaws[i];
      l.views.push_back(v);
    }
  } else if (name == "panorama") {
    ViewSpec v;
    v.name = "panorama";
    v.type = ViewProjection::kCylindrical;
    v.width = 3600, v.height = 900;
    l.views.push_back(v);
  } else if (name == "longlat") {
    ViewSpec v;
    v.name = "longlat";
    v.type = ViewProjection::kLongLat;
    v.width = 3600, v.height = 1800;
    v.elevation_min_deg = -90, v.elevation_max_deg = 90;
    l.views.push_back(v);
  } else {
    std::string known;
    for (const auto& n : PresetNames()) known += (known.empty() ? "" : ", ") + n;
    throw Error("layout '" + name + "'", "unknown preset (known: " + known + "; or give a YAML file)");
  }
  l.Check("layout " + name);
  return l;
}

Layout LoadLayout(const std::filesystem::path& path) {
  return ParseLayout(ReadFile(path), path.string(), path.stem().string());
}

namespace {
Layout ParseLayoutUnguarded(const std::string& text, const std::string& source, const std::string& name) {
  const YamlReader r(source);
  const YAML::Node root = r.Load(text);
  HOVS_REQUIRE(root.IsMap(), source, "expected a YAML mapping with 'views'");
  r.OnlyKeys(root, "", {"name", "views"});
  Layout l;
  l.name = root["name"] ? r.String(root["name"], "name") : name;
  YAML::Node views;
  r.Require(root, "", "views", &views);
  HOVS_REQUIRE(views.IsSequence() && views.size() > 0, r.Where(views, "views"), "expected a list of views");
  for (size_t i = 0; i < views.size(); ++i) {
    const YAML::Node& n = views[i];
    const std::string key = "views[" + std::to_string(i) + "]";
    r.OnlyKeys(n, key,
               {"name", "unit", "type", "width", "height", "yaw", "pitch", "roll", "hfov", "elevation_min",
                "elevation_max", "azimuth_centre", "azimuth_span"});
    ViewSpec v;
    YAML::Node t;
    v.name = r.String(r.Require(n, key, "name", &t), key + ".name");
    if (n["unit"]) v.unit = r.String(n["unit"], key + ".unit");
    HOVS_REQUIRE(!n["unit"] || !v.unit.empty(), r.Where(n["unit"], key + ".unit"), "an empty unit name");
    const std::string type = n["type"] ? r.String(n["type"], key + ".type") : "perspective";
    if (type == "perspective")
      v.type = ViewProjection::kPerspective;
    else if (type == "cylindrical")
      v.type = ViewProjection::kCylindrical;
    else if (type == "longlat")
      v.type = ViewProjection::kLongLat;
    else
      throw Error(r.Where(n["type"], key + ".type"),
                  "unknown view type '" + type + "' (known: perspective, cylindrical, longlat)");
    if (v.type == ViewProjection::kLongLat) v.elevation_min_deg = -90, v.elevation_max_deg = 90;
    if (v.type != ViewProjection::kPerspective) v.width = 3600, v.height = 900;
    const auto num = [&](const char* k, double* out) {
      if (n[k]) *out = r.Number(n[k], key + "." + k);
    };
    const auto integer = [&](const char* k, int* out) {
      if (n[k]) *out = r.Integer(n[k], key + "." + k);
    };
    integer("width", &v.width);
    integer("height", &v.height);
    const bool perspective = v.type == ViewProjection::kPerspective;
    for (const char* k : {"yaw", "pitch", "roll", "hfov"})
      HOVS_REQUIRE(perspective || !n[k], r.Where(n[k], key + "." + k), "'", k, "' applies to perspective views only");
    for (const char* k : {"elevation_min", "elevation_max", "azimuth_centre", "azimuth_span"})
      HOVS_REQUIRE(!perspective || !n[k], r.Where(n[k], key + "." + k), "'", k, "' applies to panoramas only");
    num("yaw", &v.yaw_deg);
    num("pitch", &v.pitch_deg);
    num("roll", &v.roll_deg);
    num("hfov", &v.hfov_deg);
    num("elevation_min", &v.elevation_min_deg);
    num("elevation_max", &v.elevation_max_deg);
    num("azimuth_centre", &v.azimuth_centre_deg);
    num("azimuth_span", &v.azimuth_span_deg);
    v.Check(r.Where(n, key));
    l.views.push_back(v);
  }
  l.Check(source);
  return l;
}
}  // namespace

Layout ParseLayout(const std::string& text, const std::string& source, const std::string& name) {
  return WithYamlErrors(source, [&] { return ParseLayoutUnguarded(text, source, name); });
}

ModelField FieldOfModel(const AnyModel& model) {
  const int w = model.width(), h = model.height();
  const int step = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(w) * h / 250000.0)));
  std::vector<double> el;
  for (int v = 0; v < h; v += step)
    for (int u = 0; u < w; u += step) {
      Vec3d b;
      if (model.MirrorFromImg(Vec2d(u, v), &b)) el.push_back(std::asin(std::clamp(b.z(), -1.0, 1.0)) * 180 / M_PI);
    }
  ModelField f;
  f.pixels = static_cast<int>(el.size());
  HOVS_REQUIRE(f.pixels >= 100, "the model's field", "only ", f.pixels, " valid pixels in the ", w, "x", h,
               " image: no field to fit the views to");
  const auto at = [&](double q) {
    const size_t k = std::min(el.size() - 1, static_cast<size_t>(q * (el.size() - 1)));
    std::nth_element(el.begin(), el.begin() + k, el.end());
    return el[k];
  };
  f.elevation_min_deg = at(0.001), f.elevation_max_deg = at(0.999);
  return f;
}

Layout PresetLayout(const std::string& name, const AnyModel& model) {
  Layout l = PresetLayout(name);
  if (name == "longlat") return l;
  const ModelField f = FieldOfModel(model);
  for (ViewSpec& v : l.views) {
    if (v.type == ViewProjection::kCylindrical) {
      v.elevation_min_deg = f.elevation_min_deg, v.elevation_max_deg = f.elevation_max_deg;
    } else if (v.type == ViewProjection::kPerspective) {
      // Half the vertical field of the view; pitch moved only as far as needed to keep it inside the field.
      const double half_v = std::atan(std::tan(0.5 * v.hfov_deg * M_PI / 180) * v.height / v.width) * 180 / M_PI;
      const double lo = f.elevation_min_deg + half_v, hi = f.elevation_max_deg - half_v;
      if (lo <= hi)
        v.pitch_deg = std::clamp(v.pitch_deg, lo, hi);
      else
        v.pitch_deg = 0.5 * (f.elevation_min_deg + f.elevation_max_deg);
    }
  }
  return l;
}

Layout ResolveLayout(const std::string& name_or_path, const AnyModel* model) {
  for (const auto& n : PresetNames())
    if (n == name_or_path) return model ? PresetLayout(n, *model) : PresetLayout(n);
  HOVS_REQUIRE(std::filesystem::exists(name_or_path), "layout '" + name_or_path + "'",
               "neither a preset nor an existing YAML file");
  return LoadLayout(name_or_path);
}

}  // namespace hovs::unwrap
