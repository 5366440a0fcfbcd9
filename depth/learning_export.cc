#include "depth/learning_export.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/any_model.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/large_pages.h"
#include "core/manifest.h"
#include "core/progress.h"
#include "io/image_io.h"
#include "scenes/ground_truth.h"
#include "unwrap/remap.h"

namespace hovs::depth {

namespace fs = std::filesystem;

void EquirectOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(width >= 16 && width <= 16384 && width % 2 == 0, where, "the width must be even, 16..16384 (got ", width,
               ")");
}

namespace {

// The longitude-latitude view of the whole sphere around the mirror axis.
unwrap::Layout EquirectLayout(int width) {
  unwrap::ViewSpec v;
  v.name = "equirect";
  v.type = ViewProjection::kLongLat;
  v.width = width, v.height = width / 2;
  v.elevation_min_deg = -90, v.elevation_max_deg = 90;
  v.azimuth_centre_deg = 0, v.azimuth_span_deg = 360;
  return {"equirect", {v}};
}

struct UnitExport {
  std::string name;
  unwrap::RemapTable table;
  std::vector<float> map_x, map_y;  // level-0 source coordinates, -1 where invalid
};

// One view of one frame: the RGB view, and range and mask from the nearest source pixel's ground truth.
// Returns the number of valid pixels.
int64_t ExportView(const UnitExport& u, const fs::path& image, const fs::path& exr, const fs::path& out,
                   const std::string& frame) {
  const unwrap::Image8 src = unwrap::LoadImage8(image);
  HOVS_REQUIRE(src.channels == 3, image.string(), "expected an RGB render");
  unwrap::Remapper remapper(u.table);
  std::vector<unwrap::Image8> views;
  remapper.Run(src.View(unwrap::PixelFormat::kRgb8), unwrap::Interpolation::kBilinear, &views);
  const io::ExrChannels truth = io::ReadExr(exr);
  HOVS_REQUIRE(truth.width == src.width && truth.height == src.height, exr.string(), "is ", truth.width, " x ",
               truth.height, "; its image is ", src.width, " x ", src.height);
  const std::vector<float>& range = truth.at("Z");
  const std::vector<float>& mask = truth.at("mask");
  const auto& view = views[0];
  const size_t n = size_t(view.width) * view.height;
  std::vector<float> z(n, 0.f), m(n, 0.f), rgb(n * 3);
  int64_t valid = 0;
  for (size_t k = 0; k < n; ++k) {
    const float x = u.map_x[k], y = u.map_y[k];
    const bool in = x >= 0 && y >= 0;
    const int ix = in ? std::min(src.width - 1, int(std::lround(x))) : 0;
    const int iy = in ? std::min(src.height - 1, int(std::lround(y))) : 0;
    const size_t s = size_t(iy) * src.width + ix;
    const bool ok = in && mask[s] > 0.5f;
    m[k] = ok ? 1.f : 0.f;
    z[k] = ok && std::isfinite(range[s]) ? range[s] : 0.f;
    for (int c = 0; c < 3; ++c) rgb[3 * k + c] = ok ? view.data[3 * k + c] / 255.f : 0.f;
    valid += ok;
  }
  io::WriteImage(out / u.name / "rgb" / (frame + ".png"), view.width, view.height, 3, rgb.data(), rgb.size(), 8);
  io::WriteImage(out / u.name / "mask" / (frame + ".png"), view.width, view.height, 1, m.data(), m.size(), 8);
  // Channel Y: what cv2.imread and most readers take from a one-channel EXR (a channel named Z reads as zeros).
  io::WriteExr(
      out / u.name / "range" / (frame + ".exr"), view.width, view.height, {"Y"}, z.data(),
      {{"hovs:what", "range (m) from the viewpoint F1 along the pixel's ray; 0 where the mask is 0"},
       {"hovs:layout", "equirectangular: azimuth = 180 - 360 (u + 0.5) / W, elevation = 90 - 180 (v + 0.5) / H"}});
  return valid;
}

}  // namespace

size_t EquirectMemoryBytes(int width, size_t units) {
  const size_t pixels = size_t(width) * size_t(width / 2);
  // Per unit: map_x, map_y (floats) and the remap table's dense tiles at worst as much again; per view: the 8-bit
  // view, RGB floats, range and mask floats, and the PNG encoder's copy.
  return units * pixels * 16 + pixels * (3 + 12 + 4 + 4 + 12);
}

EquirectExport ExportEquirect(const fs::path& manifest_path, const EquirectOptions& options, const fs::path& folder,
                              const nlohmann::json& versions) {
  options.Check("--width");
  const nlohmann::json manifest = LoadDatasetManifest(manifest_path);
  const std::string where = manifest_path.string();
  RequireMemory("--width",
                "an equirectangular export of " + std::to_string(manifest["units"].size()) + " units at " +
                    std::to_string(options.width) + " x " + std::to_string(options.width / 2),
                EquirectMemoryBytes(options.width, manifest["units"].size()), AvailableMemoryBytes(),
                "give a smaller --width");
  if (options.progress)
    std::fprintf(stderr, "building the %d x %d maps of %zu units\n", options.width, options.width / 2,
                 manifest["units"].size());
  std::vector<UnitExport> units;
  for (const auto& uj : manifest["units"]) {
    const std::string name = uj["name"].get<std::string>();
    const auto unit = scenes::UnitFromJson(uj, where + " (units)");
    UnitExport u{name,
                 unwrap::BuildRemapTable(AnyModel::Exact(unit.rig, 10.0, where + " (unit " + name + ")"),
                                         EquirectLayout(options.width), {}, versions.dump()),
                 {},
                 {}};
    u.table.DecodeView(0, &u.map_x, &u.map_y);
    for (const char* sub : {"rgb", "range", "mask"}) fs::create_directories(folder / name / sub);
    units.push_back(std::move(u));
  }
  EquirectExport result;
  result.units = static_cast<int>(units.size());
  nlohmann::json poses = nlohmann::json::array();
  int64_t valid = 0, total = 0;
  size_t views_total = 0, views_done = 0;
  for (const auto& f : manifest["frames"]) views_total += f["views"].size();
  const ProgressLine progress("view", views_total, options.progress);
  for (const auto& f : manifest["frames"]) {
    const std::string frame = "frame" + std::to_string(f["id"].get<int64_t>());
    nlohmann::json fp = {{"frame", frame}, {"id", f["id"]}, {"units", nlohmann::json::object()}};
    for (const auto& v : f["views"]) {
      HOVS_REQUIRE(v.contains("ground_truth"), where, "frame ", f["id"].get<int64_t>(),
                   " has no ground truth: the export needs a rendered dataset");
      HOVS_REQUIRE(v["ground_truth"].contains("exr"), where, "frame ", f["id"].get<int64_t>(),
                   " has no ground-truth image: the export needs its Z and mask channels (hovs dataset --truth "
                   "default or all)");
      progress.Step(views_done + 1, views_done, views_total - views_done);
      ++views_done;
      const std::string unit = v["unit"].get<std::string>();
      const UnitExport* u = nullptr;
      for (const auto& candidate : units)
        if (candidate.name == unit) u = &candidate;
      const fs::path sidecar = ManifestPath(manifest_path, v["ground_truth"]["sidecar"]);
      const nlohmann::json side = ReadJsonFile(sidecar);
      HOVS_REQUIRE(side.is_object() && side.contains("unit"), sidecar.string(), "not a hovs ground-truth sidecar");
      const Rigid3d world_from_mirror =
          scenes::UnitFromJson(side["unit"], sidecar.string() + " (unit)").world_from_mirror;
      valid += ExportView(*u, ManifestPath(manifest_path, v["image"]),
                          ManifestPath(manifest_path, v["ground_truth"]["exr"]), folder, frame);
      total += int64_t(options.width) * (options.width / 2);
      fp["units"][unit] = {{"world_from_mirror", scenes::PoseToJson(world_from_mirror)},
                           {"rgb", unit + "/rgb/" + frame + ".png"},
                           {"range", unit + "/range/" + frame + ".exr"},
                           {"mask", unit + "/mask/" + frame + ".png"}};
    }
    poses.push_back(fp);
    ++result.frames;
  }
  result.valid_fraction = total ? double(valid) / double(total) : 0;
  const nlohmann::json j = {
      {"tool", "hovs export --to equirect"},
      {"dataset", manifest_path.string()},
      {"versions", versions},
      {"width", options.width},
      {"height", options.width / 2},
      {"layout",
       {{"frame", "the unit's mirror frame: origin at the viewpoint F1, z along the mirror axis"},
        {"column", "azimuth_deg = 180 - 360 (u + 0.5) / W, from +x towards +y"},
        {"row", "elevation_deg = 90 - 180 (v + 0.5) / H"},
        {"point", "range * (cos el cos az, cos el sin az, sin el); world = world_from_mirror * point"},
        {"range", "float32 EXR, one channel named Y (cv2.imread reads it), metres; 0 where the mask is 0"},
        {"mask", "255 where the pixel sees the scene through the mirror"}}},
      {"valid_fraction", result.valid_fraction},
      {"frames", poses}};
  WriteFileAtomic(folder / "poses.json", j.dump(1) + "\n");
  return result;
}

}  // namespace hovs::depth
