// hovs depth: dense and sparse binocular depth from a two-unit dataset manifest (synthetic or real).
//
//   hovs depth --dataset results/street/dataset.json --out results/street-depth
// Models: the manifest's units (the exact rigs of a synthetic set), or --left-model / --right-model
// (calib_results.txt or calibration.json) with the relative pose of the units from the manifest. Output folder
// (replaced atomically): rectified_left.png, rectified_right.png, disparity.png, range.exr (Z, Z.sigma),
// points.ply, points.vtp, depth.json (config, timings, and with ground truth the error table per distance band).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "depth/evaluation.h"
#include "depth/stereo.h"
#include "raytrace/render.h"
#include "scenes/ground_truth.h"
#include "io/image_io.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

struct DepthCommandOptions {
  std::string dataset, out = "results/depth", left, right, left_model, right_model, stereo, model_kind = "auto";
  int frame = 0, width = 2048, height = 512, disparities = 320, block = 5, max_points = 200000;
  double sigma_px = 0.5, max_rel_sigma = 0.05;
  std::string matcher = "coarse-to-fine";
  int refine_radius = 3;
};

struct View {
  std::string unit;
  fs::path image, exr;
};

// The two units and their views of --frame in the manifest.
struct DepthFrame {
  raytrace::CatadioptricUnit left, right;
  View left_view, right_view;
};

DepthFrame LoadDepthFrame(const DepthCommandOptions& o) {
  const fs::path manifest(o.dataset);
  const auto m = LoadDatasetManifest(manifest);
  const auto& units = m.at("units");
  HOVS_REQUIRE(units.size() >= 2, o.dataset, "depth needs two units; the manifest has ", units.size());
  const auto find = [&](const std::string& name, size_t fallback) {
    if (name.empty()) return fallback;
    for (size_t i = 0; i < units.size(); ++i)
      if (units[i].at("name") == name) return i;
    throw Error(o.dataset, "no unit named '" + name + "'");
  };
  const size_t il = find(o.left, 0), ir = find(o.right, 1);
  HOVS_REQUIRE(il != ir, "--left/--right", "the two units must differ");
  DepthFrame d;
  d.left = scenes::UnitFromJson(units[il], o.dataset + " (units)");
  d.right = scenes::UnitFromJson(units[ir], o.dataset + " (units)");
  const auto& frames = m.at("frames");
  HOVS_REQUIRE(o.frame >= 0 && o.frame < int(frames.size()), "--frame", "the manifest has ", frames.size(), " frames");
  for (const auto& v : frames[o.frame].at("views")) {
    View* t = v.at("unit") == d.left.name ? &d.left_view : v.at("unit") == d.right.name ? &d.right_view : nullptr;
    if (!t) continue;
    t->unit = v.at("unit");
    t->image = manifest.parent_path() / v.at("image").get<std::string>();
    if (v.contains("ground_truth") && v["ground_truth"].contains("exr"))
      t->exr = manifest.parent_path() / v["ground_truth"]["exr"].get<std::string>();
  }
  HOVS_REQUIRE(!d.left_view.unit.empty() && !d.right_view.unit.empty(), o.dataset, "frame ", o.frame,
               " lacks a view of both units");
  return d;
}

// The models (the manifest's exact rigs or the calibrated ones) and the relative pose (the manifest's or
// --stereo's); `pose_source` says which.
depth::StereoRig RigFor(const DepthCommandOptions& o, const DepthFrame& f, std::string* pose_source) {
  depth::StereoRig rig{
      o.left_model.empty() ? AnyModel::Exact(f.left.rig) : LoadCalibratedModel(o.left_model, o.model_kind),
      o.right_model.empty() ? AnyModel::Exact(f.right.rig) : LoadCalibratedModel(o.right_model, o.model_kind),
      f.right.world_from_mirror.Inverse() * f.left.world_from_mirror};
  *pose_source = "manifest";
  if (!o.stereo.empty()) {
    const auto sj = ReadJsonFile(o.stereo);
    HOVS_REQUIRE(sj.is_object() && sj.contains("right_from_left"), o.stereo,
                 "not a hovs stereo-calibrate result (no right_from_left)");
    rig.right_from_left = scenes::PoseFromJson(sj["right_from_left"], o.stereo + " (right_from_left)");
    *pose_source = o.stereo;
  }
  return rig;
}

void WriteImage8(const fs::path& path, const unwrap::Image8& im) {
  std::vector<float> f(im.data.size());
  for (size_t k = 0; k < f.size(); ++k) f[k] = im.data[k] / 255.f;
  io::WriteImage(path, im.width, im.height, im.channels, f, 8);
}

// The rectified pair, the disparity, the range image and the point clouds. Returns the points written.
size_t WriteDepthOutputs(const fs::path& folder, const DepthCommandOptions& o, const depth::Rectification& rect,
                         const depth::DenseDepth& d, const unwrap::Image8& left, const unwrap::Image8& right,
                         const nlohmann::json& versions) {
  WriteImage8(folder / "rectified_left.png", left);
  WriteImage8(folder / "rectified_right.png", right);
  std::vector<float> f(d.disparity.size());
  for (size_t k = 0; k < f.size(); ++k) f[k] = d.disparity[k] > 0 ? float(d.disparity[k] / o.disparities) : 0.f;
  io::WriteImage(folder / "disparity.png", d.width, d.height, 1, f, 16);
  depth::WriteRangeExr(folder / "range.exr", d,
                       {{"hovs:what", "range from the left viewpoint (Z) and its sigma (Z.sigma), m, rectified grid"},
                        {"hovs:dataset", o.dataset},
                        {"hovs:versions", versions.dump()}});
  std::vector<depth::ColouredPoint> pts;
  std::vector<float> sig;
  depth::SubsampledCloud(rect, d, left, o.max_points, &pts, &sig);
  depth::WritePly(folder / "points.ply", pts);
  depth::WriteVtp(folder / "points.vtp", pts, sig);
  return pts.size();
}

int RunDepth(const DepthCommandOptions& o, const GlobalOptions& global) {
  depth::RectifyOptions ro;
  ro.width = o.width, ro.height = o.height;
  ro.Check("--width/--height");
  depth::DenseOptions dop;
  dop.num_disparities = o.disparities, dop.block_size = o.block;
  dop.coarse_to_fine = o.matcher == "coarse-to-fine", dop.refine_radius = o.refine_radius;
  dop.sigma_disparity_px = o.sigma_px, dop.max_relative_sigma = o.max_rel_sigma;
  dop.Check("--num-disparities/--block-size/--refine-radius/--sigma-disparity/--max-relative-sigma");
  HOVS_REQUIRE(dop.num_disparities < ro.width, "--num-disparities", "must be smaller than --width (",
               dop.num_disparities, " >= ", ro.width, ")");
  const DepthFrame frame = LoadDepthFrame(o);
  const View &vl = frame.left_view, &vr = frame.right_view;
  std::string pose_source;
  const depth::StereoRig rig = RigFor(o, frame, &pose_source);
  const unwrap::Image8 il8 = LoadImage8(vl.image), ir8 = LoadImage8(vr.image);
  const int wl = il8.width, hl = il8.height, wr = ir8.width, hr = ir8.height;
  HOVS_REQUIRE(wl == wr && hl == hr, o.dataset, "the two images differ in size (", wl, " x ", hl, " and ", wr, " x ",
               hr, ")");
  HOVS_REQUIRE(wl == rig.left.width() && hl == rig.left.height() && wr == rig.right.width() && hr == rig.right.height(),
               vl.image.string(), "the images are ", wl, " x ", hl, " but the models are for ", rig.left.width(), " x ",
               rig.left.height());
  HOVS_REQUIRE(il8.channels == ir8.channels, o.dataset, "the two images differ in channels");

  const auto t0 = std::chrono::steady_clock::now();
  const depth::Rectification rect = OnInput(o.dataset, [&] { return depth::Rectify(rig, ro); });
  const double rectify_build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const auto fmt = il8.channels == 3 ? unwrap::PixelFormat::kRgb8 : unwrap::PixelFormat::kGray8;
  unwrap::Remapper ml(rect.left), mr(rect.right);
  std::vector<unwrap::Image8> left, right;
  const auto t1 = std::chrono::steady_clock::now();
  ml.Run(il8.View(fmt), unwrap::Interpolation::kBilinear, &left);
  mr.Run(ir8.View(fmt), unwrap::Interpolation::kBilinear, &right);
  const double rectify_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  const depth::DenseDepth d =
      OnInput(o.dataset, [&] { return depth::ComputeDenseDepth(rect, left[0], right[0], dop); });

  StagedDirectory staged(o.out, "depth");
  const nlohmann::json versions = Versions();
  const size_t points = WriteDepthOutputs(staged.staging(), o, rect, d, left[0], right[0], versions);
  const size_t nvalid = std::count(d.valid.begin(), d.valid.end(), 1);
  nlohmann::json j = {{"tool", "hovs depth"},
                      {"versions", versions},
                      {"dataset", o.dataset},
                      {"frame", o.frame},
                      {"units", {frame.left.name, frame.right.name}},
                      {"models", {rig.left.KindName(), rig.right.KindName()}},
                      {"baseline_m", rect.baseline},
                      {"relative_pose_from", pose_source},
                      {"rectification",
                       {{"width", ro.width},
                        {"height", ro.height},
                        {"theta_deg", {ro.theta_min_deg, ro.theta_max_deg}},
                        {"phi_deg", {ro.phi_min_deg, ro.phi_max_deg}},
                        {"dtheta_deg", rect.dtheta * 180 / M_PI}}},
                      {"matcher",
                       {{"kind", o.matcher},
                        {"sgbm_mode", "3way"},
                        {"num_disparities", dop.num_disparities},
                        {"block_size", dop.block_size},
                        {"refine_radius", dop.refine_radius}}},
                      {"mask",
                       {{"min_theta_deg", dop.min_theta_deg},
                        {"max_relative_sigma", dop.max_relative_sigma},
                        {"sigma_disparity_px", dop.sigma_disparity_px}}},
                      {"valid_pixels", nvalid},
                      {"points_written", points},
                      {"timing_ms",
                       {{"rectification_tables", rectify_build_ms},
                        {"rectify", rectify_ms},
                        {"matching", d.match_ms},
                        {"dense_total", d.total_ms}}}};
  std::string table;
  if (!vl.exr.empty()) {
    // Ground truth: the left unit's range channel at each rectified pixel's source pixel.
    const auto exr = io::ReadExr(vl.exr);
    HOVS_REQUIRE(exr.width == wl && exr.height == hl, vl.exr.string(), "the ground truth is ", exr.width, " x ",
                 exr.height, " but its image is ", wl, " x ", hl);
    const depth::DenseDepthEvaluation e = depth::EvaluateDenseDepth(rect, d, exr.at("Z"), exr.width);
    table = depth::DenseBandsTable(e);
    j["ground_truth"] = {{"exr", vl.exr.string()}, {"bands", depth::DenseBandsJson(e)}, {"error_map", "error_map.png"}};
    io::WriteImage(staged.staging() / "error_map.png", d.width, d.height, 3, e.error_map, 8);
  }
  WriteFileAtomic(staged.staging() / "depth.json", j.dump(1));
  staged.Commit();
  if (!global.quiet) {
    std::printf("hovs depth: baseline %.4f m, %zu valid pixels of %d x %d, matching %.0f ms -> %s\n", rect.baseline,
                nvalid, d.width, d.height, d.match_ms, o.out.c_str());
    if (!table.empty()) std::printf("against the range channel of %s:\n%s", vl.unit.c_str(), table.c_str());
  }
  return 0;
}

}  // namespace

Runner SetupDepth(CLI::App* sub, const GlobalOptions* global) {
  auto o = std::make_shared<DepthCommandOptions>();
  sub->add_option("--dataset", o->dataset, "dataset manifest with two units (dataset.json)")->required();
  sub->add_option("--left", o->left, "left unit name (default: the first)");
  sub->add_option("--right", o->right, "right unit name (default: the second)");
  sub->add_option("--left-model", o->left_model,
                  "calibrated model of the left unit (calib_results.txt or calibration.json)");
  sub->add_option("--model-kind", o->model_kind,
                  "with calibration.json models: auto (physical if present) | physical | polynomial | unified")
      ->capture_default_str();
  sub->add_option("--right-model", o->right_model, "calibrated model of the right unit");
  sub->add_option("--stereo", o->stereo,
                  "relative pose from hovs stereo-calibrate (stereo.json) instead of the manifest's");
  AddBounded(sub, "--frame", &o->frame, "frame index in the manifest", 0, 1e9);
  AddBounded(sub, "--width", &o->width, "rectified width (angle from the baseline)", 16, 16384);
  AddBounded(sub, "--height", &o->height, "rectified height (angle around the baseline)", 16, 16384);
  AddBounded(sub, "--num-disparities", &o->disparities, "SGBM disparity range, multiple of 16", 16, 4096);
  AddBounded(sub, "--block-size", &o->block, "SGBM block size (odd)", 1, 21);
  sub->add_option(
         "--matcher", o->matcher,
         "coarse-to-fine (SGBM at half resolution + block search at full; about 4x faster) | sgbm (full resolution)")
      ->capture_default_str()
      ->check(CLI::IsMember({"coarse-to-fine", "sgbm"}));
  AddBounded(sub, "--refine-radius", &o->refine_radius, "coarse-to-fine: block search radius, columns", 2, 16);
  AddBounded(sub, "--sigma-disparity", &o->sigma_px, "matching noise for sigma, px", 0, 100, true);
  AddBounded(sub, "--max-relative-sigma", &o->max_rel_sigma, "mask where sigma / range exceeds this", 0, 10, true);
  AddBounded(sub, "--max-points", &o->max_points, "points written to PLY / VTP (evenly subsampled)", 1, 1e9);
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  return [o, global]() { return RunDepth(*o, *global); };
}

}  // namespace hovs::apps
