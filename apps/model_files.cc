#include "apps/model_files.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "calib/camera_formats.h"
#include "calib/model_io.h"
#include "calib/ocam_io.h"
#include "calib/omnidir_io.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "raytrace/render.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"
#include "io/image_io.h"

namespace hovs::apps {

namespace {
bool EndsWith(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}
namespace fs = std::filesystem;

constexpr const char* kModelKinds =
    "a scene YAML, dataset.json, calib_results.txt, an OpenCV omnidir or MEI YAML, a Kalibr camchain or a hovs "
    "calibration.json";

// A model file must be one of kModelKinds: an image or other binary given by mistake is named as such instead of
// failing as "not valid JSON at line 1".
void RequireModelText(const fs::path& path, const std::string& where) {
  HOVS_REQUIRE(!fs::is_directory(path), where, "is a folder; give the model file itself (", kModelKinds, ")");
  std::string head(16, '\0');
  {
    std::ifstream in(path, std::ios::binary);
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<size_t>(std::max<std::streamsize>(0, in.gcount())));
  }
  const bool png = head.rfind("\x89PNG", 0) == 0, jpeg = head.rfind("\xFF\xD8\xFF", 0) == 0;
  const bool tiff = head.rfind("II*", 0) == 0 || head.rfind("MM\0*", 0) == 0, exr = head.rfind("v/1\x01", 0) == 0;
  HOVS_REQUIRE(!(png || jpeg || tiff || exr), where, "is an image, not a camera model (expected ", kModelKinds, ")");
  HOVS_REQUIRE(head.find('\0') == std::string::npos, where, "is a binary file, not a camera model (expected ",
               kModelKinds, ")");
}

// The image size a user gave (--image-size) must be the model's own where it has one.
AnyModel WithSize(AnyModel m, ImageSize size, const std::string& where) {
  if (size.width > 0 && size.height > 0)
    HOVS_REQUIRE(m.width() == size.width && m.height() == size.height, where, "is for ", m.width(), " x ", m.height(),
                 " images, not ", size.width, " x ", size.height, " (--image-size)");
  return m;
}
AnyModel LoadModelSpecAnySize(const std::string& spec, const std::string& unit, double scene_distance, ImageSize size);
AnyModel LoadCalibratedModelAnySize(const std::filesystem::path& path, const std::string& prefer, double scene_distance,
                                    ImageSize size);
}  // namespace

AnyModel LoadCalibratedModel(const std::filesystem::path& path, const std::string& prefer, double scene_distance,
                             ImageSize size) {
  return WithSize(LoadCalibratedModelAnySize(path, prefer, scene_distance, size), size, path.string());
}

namespace {
AnyModel LoadCalibratedModelAnySize(const std::filesystem::path& path, const std::string& prefer, double scene_distance,
                                    ImageSize size) {
  RequireModelText(path, path.string());
  HOVS_REQUIRE(prefer == "auto" || prefer == "physical" || prefer == "polynomial" || prefer == "unified",
               "--model-kind", "expected auto, physical, polynomial or unified (got '", prefer, "')");
  if (path.extension() == ".yaml" || path.extension() == ".yml" || path.extension() == ".xml") {
    HOVS_REQUIRE(prefer == "auto" || prefer == "unified", path.string(),
                 "an OpenCV omnidir file holds the unified model only (--model-kind ", prefer, ")");
    const auto f = calib::LoadOmnidirYaml(path);
    return AnyModel::Unified(calib::WithImageSize(f, size.width, size.height, path.string()), f.annulus_min,
                             f.annulus_max, path.string());
  }
  if (prefer == "unified") {
    // calibration.json names its OpenCV YAML file, written beside it.
    const auto j = ReadJsonFile(path);
    HOVS_REQUIRE(j.contains("unified") && j["unified"].contains("opencv_yaml"), path.string(),
                 "has no unified model (a calibration.json of hovs calibrate, or its unified.yaml)");
    return LoadCalibratedModel(ContainedPath(path.parent_path(), JsonString(j["unified"], "opencv_yaml", path.string()),
                                             path.string() + " (unified.opencv_yaml)"),
                               "unified", scene_distance, size);
  }
  if (path.extension() != ".txt" && prefer != "polynomial") {
    const auto j = ReadJsonFile(path);
    if (j.contains("physical") && j["physical"].contains("unit"))
      return AnyModel::Exact(scenes::UnitFromJson(j["physical"]["unit"], path.string() + " (physical.unit)").rig,
                             scene_distance, path.string() + " (physical.unit)");
    HOVS_REQUIRE(prefer != "physical", path.string(), "has no physical model (calibrate with --physical)");
  }
  return AnyModel::Polynomial(calib::LoadPolynomialModelFile(path), path.string());
}
}  // namespace

// The model named on the command line; `unit` selects a unit of a scene or manifest.
AnyModel LoadModelSpec(const std::string& spec, const std::string& unit, double scene_distance, ImageSize size) {
  return WithSize(LoadModelSpecAnySize(spec, unit, scene_distance, size), size, spec);
}

namespace {
AnyModel LoadModelSpecAnySize(const std::string& spec, const std::string& unit, double scene_distance, ImageSize size) {
  HOVS_REQUIRE(std::isfinite(scene_distance) && scene_distance > 0 && scene_distance <= 1e6, "--scene-distance",
               "must be in (0, 1e6] m (got ", scene_distance, ")");
  const fs::path path(spec);
  RequireFile(path, "a model file");
  RequireModelText(path, spec);
  const auto pick = [&](size_t n, const auto& name_of) {
    if (unit.empty()) return size_t(0);
    for (size_t i = 0; i < n; ++i)
      if (name_of(i) == unit) return i;
    throw Error("--unit " + unit, "no such unit in " + spec);
  };
  if (EndsWith(spec, ".yaml") || EndsWith(spec, ".yml")) {
    const std::string text = ReadFile(path);
    if (calib::LooksLikeOmnidirYaml(text)) return LoadCalibratedModel(path, "unified", scene_distance, size);
    if (calib::LooksLikeMeiYaml(text)) return AnyModel::Unified(calib::ParseMeiYaml(text, spec), 0, 0, spec);
    if (calib::LooksLikeKalibrCamchain(text)) {
      const auto cams = calib::ParseKalibrCamchain(text, spec);
      const size_t i = pick(cams.size(), [&](size_t k) { return "cam" + std::to_string(k); });
      const std::string where = spec + " (cam" + std::to_string(i) + ")";
      return AnyModel::Unified(calib::UnifiedFromKalibr(cams[i], where), 0, 0, where);
    }
    const auto cfg = scenes::LoadSceneConfig(path);
    const auto& units = cfg.description.units;
    const size_t i = pick(units.size(), [&](size_t k) { return units[k].name; });
    return AnyModel::Exact(units[i].rig, scene_distance, spec + " (unit " + units[i].name + ")");
  }
  if (EndsWith(spec, ".xml")) return LoadCalibratedModel(path, "unified", scene_distance, size);
  if (EndsWith(spec, ".txt")) return AnyModel::Polynomial(calib::LoadPolynomialModelFile(path), spec);
  const auto j = ReadJsonFile(path);
  if (j.is_object() && JsonText(j, "format") == "hovs-dataset") {
    CheckDatasetManifest(j, path.string());  // units are objects with string names from here on
    const auto& units = j["units"];
    HOVS_REQUIRE(!units.empty(), path.string(), "the manifest lists no units");
    const size_t i = pick(units.size(), [&](size_t k) { return units[k]["name"].get<std::string>(); });
    return AnyModel::Exact(scenes::UnitFromJson(units[i], spec + " (units)").rig, scene_distance,
                           spec + " (units[" + std::to_string(i) + "])");
  }
  return LoadCalibratedModel(path, "auto", scene_distance);
}
}  // namespace

std::vector<std::string> ModelUnitNames(const std::string& spec) {
  const fs::path path(spec);
  RequireFile(path, "a model file");
  std::vector<std::string> names;
  if (EndsWith(spec, ".yaml") || EndsWith(spec, ".yml")) {
    const std::string text = ReadFile(path);
    if (calib::LooksLikeKalibrCamchain(text)) {
      const size_t n = calib::ParseKalibrCamchain(text, spec).size();
      for (size_t k = 0; k < n; ++k) names.push_back("cam" + std::to_string(k));
    } else if (!calib::LooksLikeOmnidirYaml(text) && !calib::LooksLikeMeiYaml(text)) {
      for (const auto& u : scenes::LoadSceneConfig(path).description.units) names.push_back(u.name);
    }
  } else if (EndsWith(spec, ".json")) {
    const auto j = ReadJsonFile(path);
    if (j.is_object() && JsonText(j, "format") == "hovs-dataset") {
      CheckDatasetManifest(j, path.string());
      for (const auto& u : j["units"]) names.push_back(u["name"].get<std::string>());
    }
  }
  HOVS_REQUIRE(names.size() >= 2, "--model " + spec,
               "a rig layout needs a model of several units (a scene YAML, a dataset manifest or a Kalibr camchain); "
               "this file describes ",
               names.size() == 1 ? "one unit" : "a single camera");
  return names;
}

std::vector<unwrap::RigUnitModel> LoadRigUnits(const std::string& spec, double scene_distance) {
  std::vector<unwrap::RigUnitModel> out;
  for (const auto& name : ModelUnitNames(spec))
    out.push_back({name, LoadModelSpec(spec, name, scene_distance), Rigid3d(), false});
  std::vector<raytrace::CatadioptricUnit> units;
  if (EndsWith(spec, ".json")) {
    const auto m = ReadJsonFile(spec);  // kept: a range-for over a temporary's member would dangle
    for (const auto& u : m["units"]) units.push_back(scenes::UnitFromJson(u, spec + " (units)"));
  } else if (!calib::LooksLikeKalibrCamchain(ReadFile(spec))) {
    units = scenes::LoadSceneConfig(spec).description.units;
  }
  for (auto& r : out)
    for (const auto& u : units)
      if (u.name == r.name)
        r.unit_from_rig = u.world_from_mirror.Inverse() * units[0].world_from_mirror, r.has_pose = true;
  return out;
}

depth::StereoRig LoadStereoRig(const std::string& spec, const std::string& left, const std::string& right,
                               double scene_distance, const std::string& stereo_json) {
  const fs::path path(spec);
  std::vector<raytrace::CatadioptricUnit> units;
  if (EndsWith(spec, ".yaml") || EndsWith(spec, ".yml")) {
    units = scenes::LoadSceneConfig(path).description.units;
  } else {
    const auto j = ReadJsonFile(path);
    HOVS_REQUIRE(j.is_object() && JsonText(j, "format") == "hovs-dataset", "--model " + spec,
                 "depth needs the units' poses: a scene YAML or a dataset manifest");
    CheckDatasetManifest(j, path.string());
    for (const auto& u : j["units"]) units.push_back(scenes::UnitFromJson(u, spec + " (units)"));
  }
  const auto find = [&](const std::string& name) -> const raytrace::CatadioptricUnit& {
    for (const auto& u : units)
      if (u.name == name) return u;
    throw Error("--model " + spec, "no unit '" + name + "'");
  };
  const auto& l = find(left);
  const auto& r = find(right);
  depth::StereoRig rig{AnyModel::Exact(l.rig, scene_distance, spec + " (unit " + left + ")"),
                       AnyModel::Exact(r.rig, scene_distance, spec + " (unit " + right + ")"),
                       r.world_from_mirror.Inverse() * l.world_from_mirror};
  if (!stereo_json.empty()) {
    const auto sj = ReadJsonFile(stereo_json);
    HOVS_REQUIRE(sj.is_object() && sj.contains("right_from_left"), stereo_json,
                 "not a hovs stereo-calibrate result (no right_from_left)");
    rig.right_from_left = scenes::PoseFromJson(sj["right_from_left"], stereo_json + " (right_from_left)");
  }
  HOVS_REQUIRE(rig.Baseline() > 1e-3, "--model " + spec, "units ", left, " and ", right,
               " are less than 1 mm apart: no baseline for depth");
  return rig;
}

std::vector<InputFrame> ListInputs(const std::string& input, const std::string& unit) {
  const std::filesystem::path p(input);
  HOVS_REQUIRE(std::filesystem::exists(p), "--input " + input, "not found");
  std::vector<InputFrame> frames;
  if (std::filesystem::is_directory(p)) {
    // Each image's views go to a folder named after it: two images of one name (a.png, a.jpg) would write the
    // same files.
    std::map<std::string, std::filesystem::path> seen;
    for (const auto& f : ListImageFiles(p)) {
      const auto [it, fresh] = seen.emplace(f.stem().string(), f);
      HOVS_REQUIRE(fresh, "--input " + input, "two images named '", f.stem().string(), "' (",
                   it->second.filename().string(), " and ", f.filename().string(),
                   "): their views would be written to the same folder");
      frames.push_back({f.stem().string(), f});
    }
    return frames;
  }
  if (EndsWith(input, ".json")) {
    const auto m = LoadDatasetManifest(p);
    const std::string want = unit.empty() ? m.at("units")[0]["name"].get<std::string>() : unit;
    for (const auto& fr : m.at("frames"))
      for (const auto& v : fr.at("views"))
        if (v.at("unit") == want)
          frames.push_back(
              {"frame" + std::to_string(fr.at("id").get<int>()), p.parent_path() / v.at("image").get<std::string>()});
    HOVS_REQUIRE(!frames.empty(), input, "no frame of unit '", want, "'");
    return frames;
  }
  return {{p.stem().string(), p}};
}
}  // namespace hovs::apps
