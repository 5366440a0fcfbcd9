#include "apps/unwrap_rig.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

#include "apps/model_files.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/large_pages.h"
#include "core/progress.h"
#include "core/statistics.h"
#include "io/image_io.h"
#include "unwrap/layout.h"
#include "unwrap/rig_mapping.h"
#include "unwrap/view_report.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

// A frame of the rig: its name and each unit's image (missing: empty path).
struct RigFrame {
  std::string name;
  std::vector<fs::path> images;
};

std::vector<RigFrame> ListRigFrames(const std::string& input, const std::vector<std::string>& units) {
  const fs::path p(input);
  HOVS_REQUIRE(fs::exists(p), "--input " + input, "not found");
  std::map<std::string, RigFrame> frames;
  const auto add = [&](const std::string& frame, size_t unit, const fs::path& image) {
    RigFrame& f = frames[frame];
    f.name = frame;
    f.images.resize(units.size());
    HOVS_REQUIRE(f.images[unit].empty(), "--input " + input, "frame ", frame, " has two images of unit ", units[unit]);
    f.images[unit] = image;
  };
  if (fs::is_directory(p)) {
    for (size_t u = 0; u < units.size(); ++u) {
      HOVS_REQUIRE(fs::is_directory(p / units[u]), "--input " + input, "no subfolder '", units[u],
                   "': a rig's input folder holds one subfolder per unit, images paired by name");
      for (const auto& f : ListImageFiles(p / units[u])) add(f.stem().string(), u, f);
    }
  } else {
    HOVS_REQUIRE(p.extension() == ".json", "--input " + input,
                 "a rig layout takes a dataset manifest or a folder of unit subfolders");
    const auto m = LoadDatasetManifest(p);
    for (const auto& fr : m.at("frames")) {
      const std::string name = "frame" + std::to_string(fr.at("id").get<int>());
      frames[name].name = name;
      frames[name].images.resize(units.size());
      for (const auto& v : fr.at("views"))
        for (size_t u = 0; u < units.size(); ++u)
          if (v.at("unit") == units[u]) add(name, u, p.parent_path() / v.at("image").get<std::string>());
    }
  }
  std::vector<RigFrame> out;
  for (auto& [name, f] : frames) out.push_back(std::move(f));
  HOVS_REQUIRE(!out.empty(), "--input " + input, "no frames");
  return out;
}

unwrap::RigMapping BuildMapping(const RigUnwrapOptions& o, std::string* source) {
  if (!o.map.empty()) {
    *source = "loaded " + o.map;
    return unwrap::LoadRigMapping(o.map);
  }
  const std::vector<unwrap::RigUnitModel> units = LoadRigUnits(o.model, o.scene_distance);
  const unwrap::Layout layout = unwrap::ResolveLayout(o.layout, o.fixed_elevation ? nullptr : &units[0].model);
  unwrap::CheckViewsMemory("--layout " + o.layout, layout.views, AvailableMemoryBytes());
  unwrap::RemapOptions ro;
  ro.tile = o.tile;
  *source = "built from the " + std::to_string(units.size()) + " units of " + o.model;
  return unwrap::BuildRigMapping(units, layout, ro, nlohmann::json(Versions()).dump());
}

}  // namespace

std::vector<uint8_t> LoadFrameBytes(const std::filesystem::path& image, const std::string& format, int width,
                                    int height, unwrap::PixelFormat* fmt) {
  int w = 0, h = 0, c = 0;
  const io::PixelBuffer px = io::ReadImage(image, &w, &h, &c);
  if (format == "auto") {
    HOVS_REQUIRE(c == 1 || c == 3 || c == 4, image.string(), "unsupported channel count ", c);
    *fmt = c == 1 ? unwrap::PixelFormat::kGray8 : unwrap::PixelFormat::kRgb8;
  } else {
    *fmt = unwrap::ParsePixelFormat(format);
    HOVS_REQUIRE((*fmt == unwrap::PixelFormat::kRgb8) == (c >= 3), image.string(), "has ", c,
                 " channels, which is not ", format);
  }
  HOVS_REQUIRE(w == width && h == height, image.string(), "the image is ", w, " x ", h, " but the model is for ", width,
               " x ", height);
  const int oc = *fmt == unwrap::PixelFormat::kRgb8 ? 3 : 1;
  std::vector<uint8_t> bytes(size_t(w) * h * oc);
  for (size_t k = 0; k < size_t(w) * h; ++k)
    for (int ch = 0; ch < oc; ++ch)
      bytes[k * oc + ch] = uint8_t(std::lround(std::clamp(px[k * c + ch], 0.f, 1.f) * 255));
  return bytes;
}

bool IsRigUnwrap(const std::string& layout, const std::string& map) {
  if (!map.empty()) return fs::exists(map) && unwrap::IsRigMappingFile(map);
  for (const auto& n : unwrap::PresetNames())
    if (n == layout) return unwrap::PresetLayout(n).IsRig();
  return fs::exists(layout) && unwrap::LoadLayout(layout).IsRig();
}

int RunRigUnwrap(const RigUnwrapOptions& o, const GlobalOptions& global) {
  HOVS_REQUIRE(!o.input.empty() || !o.save_map.empty(), "hovs unwrap", "give --input (and/or --save-map)");
  if (!o.save_map.empty()) CheckOutputFile(o.save_map, "HOVSRIG", "a hovs rig mapping file");
  const unwrap::Interpolation interp = unwrap::ParseInterpolation(o.interp);
  const auto t0 = std::chrono::steady_clock::now();
  std::string source;
  const unwrap::RigMapping mapping = BuildMapping(o, &source);
  const double mapping_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!global.quiet)
    std::printf("hovs unwrap: %d views of %zu units, mapping %s in %.0f ms\n", mapping.ViewCount(),
                mapping.units.size(), source.c_str(), mapping_ms);
  if (o.input.empty()) {
    unwrap::SaveRigMapping(o.save_map, mapping);
    return 0;
  }
  const std::vector<RigFrame> frames = ListRigFrames(o.input, mapping.units);
  StagedDirectory staged(o.out, "unwrap");
  unwrap::RigRemapper remapper(mapping);
  std::vector<unwrap::Image8> views;
  std::vector<double> remap_ms;
  nlohmann::json frames_json = nlohmann::json::array(), unpaired = nlohmann::json::array();
  const ProgressLine progress("frame", frames.size(), !global.quiet && frames.size() > 1);
  for (size_t f = 0; f < frames.size(); ++f) {
    progress.Step(f + 1, f, frames.size() - f);
    std::vector<std::string> missing;
    for (size_t u = 0; u < mapping.units.size(); ++u)
      if (frames[f].images[u].empty()) missing.push_back(mapping.units[u]);
    if (!missing.empty()) {  // never expanded alone: a rig's views need every unit's frame of the same instant
      unpaired.push_back({{"frame", frames[f].name}, {"missing_units", missing}});
      continue;
    }
    std::vector<std::vector<uint8_t>> bytes(mapping.units.size());
    std::vector<unwrap::ImageView> srcs;
    for (size_t u = 0; u < mapping.units.size(); ++u) {
      unwrap::PixelFormat fmt;
      bytes[u] = LoadFrameBytes(frames[f].images[u], o.format, mapping.tables[u].source_width,
                                mapping.tables[u].source_height, &fmt);
      const int w = mapping.tables[u].source_width, h = mapping.tables[u].source_height;
      srcs.push_back({bytes[u].data(), w, h, bytes[u].size() / h, fmt});
    }
    const auto a = std::chrono::steady_clock::now();
    remapper.Run(srcs, interp, &views);
    remap_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
    nlohmann::json outs = nlohmann::json::object(), inputs = nlohmann::json::object();
    for (int k = 0; k < mapping.ViewCount(); ++k) {
      const std::string rel = frames[f].name + "/" + mapping.View(k).spec.name + ".png";
      std::vector<float> fl(views[k].data.begin(), views[k].data.end());
      for (float& x : fl) x /= 255.f;
      io::WriteImage(staged.staging() / rel, views[k].width, views[k].height, views[k].channels, fl, 8);
      outs[mapping.View(k).spec.name] = rel;
    }
    for (size_t u = 0; u < mapping.units.size(); ++u) inputs[mapping.units[u]] = frames[f].images[u].string();
    frames_json.push_back(
        {{"frame", frames[f].name}, {"inputs", inputs}, {"views", outs}, {"remap_ms", remap_ms.back()}});
  }
  HOVS_REQUIRE(!frames_json.empty(), "--input " + o.input, "no frame has an image of every unit (", unpaired.size(),
               " unpaired)");
  nlohmann::json views_json = nlohmann::json::array();
  for (int k = 0; k < mapping.ViewCount(); ++k) {
    nlohmann::json v = unwrap::ViewJson(mapping.View(k));
    v["unit"] = mapping.UnitName(k);
    views_json.push_back(v);
  }
  const double median_ms = Median(remap_ms);
  const nlohmann::json j = {{"tool", "hovs unwrap"},
                            {"versions", Versions()},
                            {"mapping", nlohmann::json::parse(mapping.header)},
                            {"mapping_source", source},
                            {"units", mapping.units},
                            {"interpolation", o.interp},
                            {"views", views_json},
                            {"frames", frames_json},
                            {"unpaired", unpaired},
                            {"frames_expanded", frames_json.size()},
                            {"frames_unpaired", unpaired.size()},
                            {"timing",
                             {{"mapping_ms", mapping_ms},
                              {"median_remap_ms", median_ms},
                              {"note", "remap of every unit's frame into all views in one pass, TBB threads"}}}};
  WriteFileAtomic(staged.staging() / "views.json", j.dump(1));
  if (!o.save_map.empty()) unwrap::SaveRigMapping(o.save_map, mapping);
  staged.Commit();
  if (!global.quiet) {
    std::printf("hovs unwrap: %zu frames x %d views of %zu units -> %s (median remap %.2f ms per frame)\n",
                frames_json.size(), mapping.ViewCount(), mapping.units.size(), o.out.c_str(), median_ms);
    if (!unpaired.empty())
      std::printf("hovs unwrap: %zu frames lack a unit's image and were not expanded (views.json: unpaired)\n",
                  unpaired.size());
  }
  return 0;
}

}  // namespace hovs::apps
