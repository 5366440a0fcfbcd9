// hovs unwrap: virtual perspective views and panoramas from catadioptric images, through any model.
//
//   hovs unwrap --model scenes/street.yaml --unit left --layout article --input frame.png -o out
//   hovs unwrap --model calib/calib_results.txt --layout panorama --input images/ -o out --save-map pano.hmap
//   hovs unwrap --map pano.hmap --input dataset.json -o out
// Models: a scene YAML or a dataset manifest (the exact rig of a unit), OCamCalib's calib_results.txt or hovs'
// calibration.json (polynomial). Inputs: an image, a folder of images, or a dataset manifest (every view of the
// unit). Output folder (replaced atomically): <frame>/<view>.png per input frame, views.json (each view's K and
// pose, the mapping header, timings).
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "apps/unwrap_rig.h"
#include "apps/unwrap_viewer.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/io.h"
#include "core/json.h"
#include "core/large_pages.h"
#include "core/statistics.h"
#include "raytrace/render.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"
#include "scenes/truth_views.h"
#include "unwrap/colmap_export.h"
#include "unwrap/remap.h"
#include "unwrap/view_report.h"
#include "io/image_io.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

struct UnwrapCommandOptions {
  std::string model, unit, layout = "article", input, out = "results/unwrap", map, save_map;
  std::string interp = "bilinear", format = "auto";
  double scene_distance = 10.0;
  int tile = 0;
  std::string truth_scene;
  int truth_samples = 4;
  bool interactive = false, fixed_elevation = false, colmap = false;
  std::string layout_out = "layout.yaml";
};

// Every input frame's header, checked before any mapping is built: a bad image is named first.
std::vector<io::ImageHeader> CheckFrames(const std::vector<InputFrame>& frames, const std::string& format) {
  std::vector<io::ImageHeader> headers;
  for (const auto& f : frames) {
    headers.push_back(io::ReadImageHeader(f.image));
    const int c = headers.back().channels;
    if (format == "auto")
      HOVS_REQUIRE(c == 1 || c == 3 || c == 4, f.image.string(), "unsupported channel count ", c);
    else
      HOVS_REQUIRE((unwrap::ParsePixelFormat(format) == unwrap::PixelFormat::kRgb8) == (c >= 3), f.image.string(),
                   "has ", c, " channels, which is not ", format);
  }
  return headers;
}

void CheckSizes(const std::vector<InputFrame>& frames, const std::vector<io::ImageHeader>& headers, int width,
                int height) {
  for (size_t f = 0; f < frames.size(); ++f)
    HOVS_REQUIRE(headers[f].width == width && headers[f].height == height, frames[f].image.string(), "the image is ",
                 headers[f].width, " x ", headers[f].height, " but the model is for ", width, " x ", height);
}

// The mapping: loaded from --map or built from --model and --layout; `source` says which.
unwrap::RemapTable Mapping(const UnwrapCommandOptions& o, const std::vector<InputFrame>& frames,
                           const std::vector<io::ImageHeader>& headers, std::string* source) {
  if (!o.map.empty()) {
    unwrap::RemapTable table = unwrap::LoadRemapTable(o.map);
    CheckSizes(frames, headers, table.source_width, table.source_height);
    *source = "loaded " + o.map;
    std::vector<unwrap::ViewSpec> specs;
    for (const auto& v : table.views) specs.push_back(v.spec);
    unwrap::CheckViewsMemory("--map " + o.map, specs, AvailableMemoryBytes());
    return table;
  }
  const AnyModel model = LoadModelSpec(o.model, o.unit, o.scene_distance);
  CheckSizes(frames, headers, model.width(), model.height());
  unwrap::RemapOptions ro;
  ro.tile = o.tile;
  const unwrap::Layout layout = unwrap::ResolveLayout(o.layout, o.fixed_elevation ? nullptr : &model);
  unwrap::CheckViewsMemory("--layout " + o.layout, layout.views, AvailableMemoryBytes());
  *source = std::string("built from the ") + model.KindName() + " model in " + o.model;
  return unwrap::BuildRemapTable(model, layout, ro, nlohmann::json(Versions()).dump());
}

void WriteRgb8(const fs::path& path, int width, int height, int channels, const std::vector<uint8_t>& data) {
  std::vector<float> fl(data.size());
  for (size_t k = 0; k < fl.size(); ++k) fl[k] = data[k] / 255.f;
  io::WriteImage(path, width, height, channels, fl, 8);
}

// Unwraps every frame into `folder`: <frame>/<view>.png, and beside each perspective view with a truth render
// <frame>/<view>_truth.png and its PSNR in `truth_json`. Returns the frames' records; remap_ms gets each
// frame's remap time.
nlohmann::json UnwrapFrames(const UnwrapCommandOptions& o, bool quiet, const std::vector<InputFrame>& frames,
                            const unwrap::RemapTable& table,
                            const std::vector<std::optional<std::vector<uint8_t>>>& truth, const fs::path& folder,
                            nlohmann::json* truth_json, std::vector<double>* remap_ms) {
  const unwrap::Interpolation interp = unwrap::ParseInterpolation(o.interp);
  unwrap::Remapper remapper(table);
  nlohmann::json frames_json = nlohmann::json::array();
  // The views' buffers are reused from frame to frame (Run keeps outputs of the right size): after the first
  // frame the remap time is the kernels' alone, not the first touch of fresh pages.
  std::vector<unwrap::Image8> views;
  const ProgressLine progress("frame", frames.size(), !quiet && frames.size() > 1);
  for (size_t f = 0; f < frames.size(); ++f) {
    progress.Step(f + 1, f, frames.size() - f);
    unwrap::PixelFormat fmt;
    const std::vector<uint8_t> bytes =
        LoadFrameBytes(frames[f].image, o.format, table.source_width, table.source_height, &fmt);
    const int w = table.source_width, h = table.source_height, oc = fmt == unwrap::PixelFormat::kRgb8 ? 3 : 1;
    const auto a = std::chrono::steady_clock::now();
    remapper.Run({bytes.data(), w, h, size_t(w) * oc, fmt}, interp, &views);
    remap_ms->push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
    nlohmann::json outs = nlohmann::json::object();
    for (size_t v = 0; v < views.size(); ++v) {
      const std::string& name = table.views[v].spec.name;
      const std::string rel = frames[f].name + "/" + name + ".png";
      WriteRgb8(folder / rel, views[v].width, views[v].height, views[v].channels, views[v].data);
      outs[name] = rel;
      if (!truth[v] || views[v].channels != 3) continue;
      const unwrap::ViewPsnr q = unwrap::CompareWithReference(table, static_cast<int>(v), views[v], *truth[v]);
      const std::string trel = frames[f].name + "/" + name + "_truth.png";
      WriteRgb8(folder / trel, views[v].width, views[v].height, 3, *truth[v]);
      (*truth_json)[frames[f].name][name] = {
          {"psnr_db", q.psnr_db}, {"truth", trel}, {"valid_fraction", q.valid_fraction}};
      if (!quiet)
        std::fprintf(stderr, "  %s %s: PSNR %.2f dB against the pinhole truth render\n", frames[f].name.c_str(),
                     name.c_str(), q.psnr_db);
    }
    frames_json.push_back({{"frame", frames[f].name},
                           {"input", frames[f].image.string()},
                           {"views", outs},
                           {"remap_ms", remap_ms->back()},
                           {"pixel_format", unwrap::ToString(fmt)}});
  }
  return frames_json;
}

// The frames for COLMAP, with each frame's unit pose when the input is a rendered dataset.
std::vector<unwrap::ColmapFrame> ColmapFrames(const UnwrapCommandOptions& o, const std::vector<InputFrame>& frames) {
  const bool manifest = fs::is_regular_file(o.input) && fs::path(o.input).extension() == ".json";
  const auto poses = manifest ? scenes::ViewPosesByImage(o.input) : std::map<fs::path, Rigid3d>();
  std::vector<unwrap::ColmapFrame> out;
  for (const auto& f : frames) {
    const auto it = poses.find(f.image.lexically_normal());
    out.push_back({f.name, it == poses.end() ? std::nullopt : std::optional<Rigid3d>(it->second)});
  }
  return out;
}

int RunUnwrap(const UnwrapCommandOptions& o, const GlobalOptions& global) {
  HOVS_REQUIRE(o.model.empty() != o.map.empty(), "hovs unwrap", "give either --model or --map");
  if (o.interactive) {
    HOVS_REQUIRE(!o.model.empty() && !o.input.empty(), "hovs unwrap --interactive",
                 "needs --model (views are rebuilt as you move them) and --input");
    const AnyModel model = LoadModelSpec(o.model, o.unit, o.scene_distance);
    const unwrap::Image8 im = LoadImage8(ListInputs(o.input, o.unit).front().image);
    RunUnwrapViewer(model, unwrap::ResolveLayout(o.layout, o.fixed_elevation ? nullptr : &model),
                    im.View(im.channels == 1 ? unwrap::PixelFormat::kGray8 : unwrap::PixelFormat::kRgb8), o.layout_out);
    return 0;
  }
  if (IsRigUnwrap(o.layout, o.map)) {
    HOVS_REQUIRE(o.truth_scene.empty() && !o.colmap, "--layout " + o.layout,
                 "--truth-scene and --colmap take one unit's views, not a rig's");
    return RunRigUnwrap({o.model, o.layout, o.map, o.save_map, o.input, o.out, o.interp, o.format, o.scene_distance,
                         o.tile, o.fixed_elevation},
                        global);
  }
  HOVS_REQUIRE(!o.input.empty() || !o.save_map.empty(), "hovs unwrap", "give --input (and/or --save-map)");
  HOVS_REQUIRE(o.save_map.empty() || o.map.empty(), "--save-map",
               "saves the mapping built from --model, not one "
               "loaded with --map");
  unwrap::ParseInterpolation(o.interp);
  if (!o.save_map.empty()) CheckOutputFile(o.save_map, "HOVSMAP", "a hovs mapping file");
  // The inputs, their headers and the truth scene first: a bad one is named before any mapping is built.
  const auto frames = o.input.empty() ? std::vector<InputFrame>() : ListInputs(o.input, o.unit);
  const std::vector<io::ImageHeader> headers = CheckFrames(frames, o.format);
  std::optional<scenes::SceneConfig> truth_cfg;
  if (!o.truth_scene.empty()) truth_cfg = scenes::LoadSceneConfig(o.truth_scene);
  const auto t0 = std::chrono::steady_clock::now();
  std::string source;
  const unwrap::RemapTable table = Mapping(o, frames, headers, &source);
  const double table_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!global.quiet)
    std::printf("hovs unwrap: %zu views, mapping %s in %.0f ms\n", table.views.size(), source.c_str(), table_ms);
  if (o.colmap) unwrap::FormatColmapModel(table, {});  // refuses a layout without perspective views, before any work
  // The mapping file is saved once everything else has succeeded: a failed run leaves no new file.
  if (o.input.empty()) {
    if (!o.save_map.empty()) unwrap::SaveRemapTable(o.save_map, table);
    return 0;
  }
  // Ground-truth views: pinhole renders of the scene (without the units' hardware) at the unit's viewpoint.
  std::vector<std::optional<std::vector<uint8_t>>> truth(table.views.size());
  if (truth_cfg) {
    std::vector<VirtualView<double>> views;
    for (const auto& v : table.views) views.push_back(v.view);
    truth = scenes::RenderTruthViews(*truth_cfg, o.unit, views, o.truth_samples, o.truth_scene);
  }
  StagedDirectory staged(o.out, "unwrap");
  nlohmann::json truth_json = nlohmann::json::object();
  std::vector<double> remap_ms;
  const nlohmann::json frames_json =
      UnwrapFrames(o, global.quiet, frames, table, truth, staged.staging(), &truth_json, &remap_ms);
  nlohmann::json views_json = nlohmann::json::array();
  for (const auto& vt : table.views) views_json.push_back(unwrap::ViewJson(vt));
  const double median_ms = Median(remap_ms);
  nlohmann::json j = {{"tool", "hovs unwrap"},
                      {"versions", Versions()},
                      {"mapping", nlohmann::json::parse(table.header)},
                      {"mapping_source", source},
                      {"interpolation", o.interp},
                      {"views", views_json},
                      {"frames", frames_json},
                      {"timing",
                       {{"mapping_ms", table_ms},
                        {"median_remap_ms", median_ms},
                        {"note", "remap of all views of one frame, this machine, threads: TBB default"}}}};
  if (!truth_json.empty())
    j["truth"] = {{"scene", o.truth_scene}, {"samples", o.truth_samples}, {"per_frame", truth_json}};
  if (o.colmap) {
    const unwrap::ColmapModel colmap = unwrap::FormatColmapModel(table, ColmapFrames(o, frames));
    fs::create_directories(staged.staging() / "colmap");
    WriteFileAtomic(staged.staging() / "colmap" / "cameras.txt", colmap.cameras);
    WriteFileAtomic(staged.staging() / "colmap" / "images.txt", colmap.images);
    WriteFileAtomic(staged.staging() / "colmap" / "points3D.txt", colmap.points3d);
    j["colmap"] = {{"folder", "colmap"}, {"cameras", colmap.cameras_count}, {"images", colmap.images_count}};
  }
  WriteFileAtomic(staged.staging() / "views.json", j.dump(1));
  if (!o.save_map.empty()) unwrap::SaveRemapTable(o.save_map, table);
  staged.Commit();
  if (!global.quiet)
    std::printf("hovs unwrap: %zu frames x %zu views -> %s (median remap %.2f ms per frame)\n", frames.size(),
                table.views.size(), o.out.c_str(), median_ms);
  return 0;
}

}  // namespace

Runner SetupUnwrap(CLI::App* sub, const GlobalOptions* global) {
  auto o = std::make_shared<UnwrapCommandOptions>();
  sub->add_option("--model", o->model, "scene YAML or dataset.json (exact rig), calib_results.txt or calibration.json");
  sub->add_option("--unit", o->unit, "unit name in a scene or manifest (default: the first)");
  sub->add_option("--layout", o->layout,
                  "article | panorama | longlat | binocular (two units: 3 + 3 views) | a layout YAML")
      ->capture_default_str();
  sub->add_flag("--fixed-elevation", o->fixed_elevation,
                "presets keep their fixed elevations (panorama -75..-2, article pitch -30) instead of following the "
                "model's field");
  sub->add_option("--map", o->map, "load a mapping file instead of building from --model");
  sub->add_option("--save-map", o->save_map, "save the mapping file built from --model");
  sub->add_option("-i,--input", o->input, "an image, a folder of images or a dataset manifest");
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  sub->add_option("--interp", o->interp, "bilinear | bicubic | nearest")->capture_default_str();
  sub->add_option("--format", o->format, "auto | rgb | gray | bayer_rggb (input pixel format)")->capture_default_str();
  AddBounded(sub, "--scene-distance", &o->scene_distance, "m; depth at which a non-single-viewpoint rig is unwrapped",
             0, 1e6, true);
  AddBounded(sub, "--tile", &o->tile,
             "tile size of the mapping (8, 16, 32, 64; 0: per view, 64 where every tile of the view is interpolated at "
             "that size without minifying, else 32)",
             0, 64);
  sub->add_option("--truth-scene", o->truth_scene,
                  "scene YAML the input was rendered from: render each perspective view with a pinhole camera at the "
                  "unit's viewpoint and report PSNR against it");
  AddBounded(sub, "--truth-samples", &o->truth_samples, "samples per pixel of the truth renders", 1, 4096);
  sub->add_flag("--colmap", o->colmap,
                "also write COLMAP's text model of the perspective views (colmap/: cameras.txt, images.txt, "
                "points3D.txt; world poses from a rendered dataset's ground truth)");
  sub->add_flag("--interactive", o->interactive,
                "control panel: adjust each view live on the first input frame (needs a display; s saves the layout)");
  sub->add_option("--layout-out", o->layout_out, "where --interactive saves the adjusted layout")
      ->capture_default_str();
  return [o, global]() { return RunUnwrap(*o, *global); };
}

}  // namespace hovs::apps
