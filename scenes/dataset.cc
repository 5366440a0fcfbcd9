#include "scenes/dataset.h"

#include <cmath>
#include <atomic>
#include <cstdio>
#include <future>
#include <optional>
#include <random>

#include "core/error.h"
#include "core/format.h"
#include "core/interrupt.h"
#include "core/io.h"
#include "core/json.h"
#include "core/shard_set.h"
#include "core/manifest.h"
#include "core/progress.h"
#include "raytrace/render.h"
#include "results/html.h"
#include "scenes/frame_journal.h"
#include "scenes/ground_truth.h"
#include "io/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

namespace hovs::scenes {
namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

DatasetOptions DatasetOptions::ForKind(const std::string& kind) {
  DatasetOptions o;
  o.kind = kind;
  if (kind == "stereo_aruco") {
    o.count = 12;
    o.board.kind = BoardSpec::Kind::kAruco;
    o.board.markers_x = o.board.markers_y = 5;
    o.board.marker_length = 0.2;
    o.board.marker_separation = 0.05;  // 5 x 0.2 + 4 x 0.05 = 1.2 m, the article's board
    o.board.margin = 0.02;
    o.min_distance = 1.5, o.max_distance = 3.5;
    o.min_elevation_deg = -35, o.max_elevation_deg = -6;
    o.max_tilt_deg = 30;
    o.min_visible_fraction = 0.6;
  }
  if (kind == "depth_sequence") o.count = 5;
  return o;
}

void DatasetOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(kind == "mono_calibration" || kind == "stereo_aruco" || kind == "depth_sequence", where + ".kind",
               "unknown dataset kind '", kind, "' (known: mono_calibration, stereo_aruco, depth_sequence)");
  HOVS_REQUIRE(std::isfinite(step_m) && std::abs(step_m) <= 100 && std::isfinite(heading_deg) &&
                   std::isfinite(yaw_step_deg) && std::abs(yaw_step_deg) <= 90,
               where + ".motion", "step must be a finite distance up to 100 m, yaw step up to 90 degrees");
  HOVS_REQUIRE(min_visible_fraction > 0 && min_visible_fraction <= 1, where + ".min_visible_fraction",
               "must be in (0, 1]");
  HOVS_REQUIRE(count >= 1 && count <= 10000, where + ".count", "must be in 1..10000");
  HOVS_REQUIRE(min_distance > 0 && max_distance >= min_distance, where + ".distance", "needs 0 < min <= max");
  HOVS_REQUIRE(min_elevation_deg < max_elevation_deg && max_elevation_deg < 90 && min_elevation_deg > -90,
               where + ".elevation", "needs -90 < min < max < 90 degrees");
  HOVS_REQUIRE(max_tilt_deg >= 0 && max_tilt_deg < 80, where + ".max_tilt_deg", "must be in [0, 80)");
  HOVS_REQUIRE(shard_count >= 1 && shard_count <= count && shard_index >= 0 && shard_index < shard_count,
               where + ".shard", "needs 0 <= index < shards <= frames (got shard ", shard_index, " of ", shard_count,
               " for ", count, " frames)");
  CheckBoard(board, where + ".board");
}

namespace {

struct ViewRecord {
  std::string unit, image, exr, sidecar;
};

// Renders unit u of the scene into dir: image, EXR ground truth, sidecar. Returns the manifest view.
// scratch: the frame buffers, reused from view to view (they are touched once per dataset, not per frame).
ViewRecord RenderView(const SceneConfig& cfg, const raytrace::RayScene& scene, int u, const fs::path& dir,
                      const std::string& stem, bool progress, nlohmann::json* stats, raytrace::Frame* scratch) {
  raytrace::RenderOptions ro = cfg.render;
  ro.progress = progress;
  // The sidecar (corner truth, the rig) comes from the scene; the per-pixel truth only where a channel is stored.
  const bool sidecar = ro.ground_truth, exr = sidecar && !ro.truth_file.groups.empty();
  ro.ground_truth = exr;
  raytrace::RenderInto(scene, raytrace::ViewCamera::Unit(u), ro, scratch);
  const raytrace::Frame& frame = *scratch;
  int channels = 0;
  const raytrace::PixelBuffer img =
      raytrace::ApplySensor(frame, ro.sensor, ro.seed ^ std::hash<std::string>{}(stem), &channels);
  const std::string unit = scene.description().units[u].name;
  ViewRecord v{unit, "images/" + stem + ".png", "", ""};
  // The image is compressed on its own thread while the ground truth is written (both are single-file,
  // atomic writes; an error in either is rethrown here).
  auto image_written = std::async(std::launch::async, [&] {
    io::WriteImage(dir / v.image, frame.width, frame.height, channels, img, ro.sensor.bit_depth);
  });
  struct Join {
    std::future<void>& f;
    ~Join() {
      if (f.valid()) f.wait();
    }
  } join{image_written};
  if (sidecar) {
    v.sidecar = "truth/" + stem + ".json";
    if (exr) {
      v.exr = "truth/" + stem + ".exr";
      raytrace::WriteGroundTruthExr(dir / v.exr, frame,
                                    {{"scene", cfg.name},
                                     {"unit", unit},
                                     {"frame", stem},
                                     {"world_frame", "z up, metres"},
                                     {"sidecar", v.sidecar}},
                                    ro.truth_file);
    }
    nlohmann::json side = FrameSidecar(cfg, scene, u);
    side["image"] = v.image;
    side["render"] = {{"samples", ro.samples},
                      {"seed", ro.seed},
                      {"bit_depth", ro.sensor.bit_depth},
                      {"bayer", ro.sensor.bayer},
                      {"vignetting", ro.sensor.vignetting},
                      {"full_well", ro.sensor.full_well},
                      {"read_noise", ro.sensor.read_noise}};
    WriteFileAtomic(dir / v.sidecar, side.dump(1) + "\n");
  }
  image_written.get();
  if (stats) {
    (*stats)["rays"] = frame.rays;
    (*stats)["seconds"] = frame.seconds;
  }
  return v;
}

// A thumbnail (longest side `size` px) of an image file, written next to it under thumbs/; one already there (a
// resumed run's) is kept.
std::string Thumbnail(const fs::path& dir, const std::string& image, int size) {
  const std::string existing = "thumbs/" + fs::path(image).filename().string();
  if (fs::is_regular_file(dir / existing)) return existing;
  OIIO::ImageBuf src((dir / image).string());
  HOVS_REQUIRE(src.read(0, 0, true, OIIO::TypeDesc::FLOAT), image, "cannot read for the thumbnail");
  const auto& spec = src.spec();
  const double scale = static_cast<double>(size) / std::max(spec.width, spec.height);
  const int w = std::max(1, static_cast<int>(spec.width * scale)),
            h = std::max(1, static_cast<int>(spec.height * scale));
  // Box filter over the source pixels of each thumbnail pixel (fast, no aliasing at this reduction).
  OIIO::ImageBuf dst(OIIO::ImageSpec(w, h, spec.nchannels, OIIO::TypeDesc::FLOAT));
  std::vector<float> in(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  HOVS_REQUIRE(src.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, in.data()), image,
               "cannot read for the thumbnail");
  std::vector<float> out(static_cast<size_t>(w) * h * spec.nchannels, 0.0f);
  const double sx = static_cast<double>(spec.width) / w, sy = static_cast<double>(spec.height) / h;
  for (int y = 0; y < h; ++y) {
    const int y0 = static_cast<int>(y * sy),
              y1 = std::max(y0 + 1, std::min(spec.height, static_cast<int>((y + 1) * sy)));
    for (int x = 0; x < w; ++x) {
      const int x0 = static_cast<int>(x * sx),
                x1 = std::max(x0 + 1, std::min(spec.width, static_cast<int>((x + 1) * sx)));
      float* o = &out[(static_cast<size_t>(y) * w + x) * spec.nchannels];
      for (int yy = y0; yy < y1; ++yy)
        for (int xx = x0; xx < x1; ++xx)
          for (int c = 0; c < spec.nchannels; ++c)
            o[c] += in[(static_cast<size_t>(yy) * spec.width + xx) * spec.nchannels + c];
      for (int c = 0; c < spec.nchannels; ++c) o[c] /= static_cast<float>((y1 - y0) * (x1 - x0));
    }
  }
  dst.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, out.data());
  const std::string rel = "thumbs/" + fs::path(image).filename().string();
  fs::create_directories(dir / "thumbs");
  const fs::path tmp = dir / "thumbs" / (".tmp-" + fs::path(image).filename().string());
  HOVS_REQUIRE(dst.write(tmp.string(), OIIO::TypeDesc::UINT8), rel, "cannot write thumbnail: ", dst.geterror());
  fs::rename(tmp, dir / rel);
  return rel;
}

nlohmann::json ViewJson(const ViewRecord& v) {
  nlohmann::json j = {{"unit", v.unit}, {"image", v.image}};
  if (!v.sidecar.empty()) j["ground_truth"] = {{"sidecar", v.sidecar}};
  if (!v.exr.empty()) j["ground_truth"]["exr"] = v.exr;
  return j;
}

nlohmann::json ManifestHead(const SceneConfig& cfg, const std::string& kind, uint64_t seed,
                            const std::map<std::string, std::string>& versions) {
  nlohmann::json m;
  m["format"] = "hovs-dataset";
  m["version"] = 1;
  m["kind"] = kind;
  m["name"] = cfg.name;
  m["seed"] = seed;
  m["render_seed"] = cfg.render.seed;
  m["versions"] = versions;
  m["scene"] = {{"source", cfg.source}, {"text", cfg.text}};
  nlohmann::json units = nlohmann::json::array();
  for (const auto& u : cfg.description.units) units.push_back(UnitToJson(u));
  m["units"] = units;
  return m;
}

}  // namespace

void RenderSceneFolder(const SceneConfig& cfg, const fs::path& out, bool progress,
                       const std::map<std::string, std::string>& versions) {
  StagedDirectory stage(out, "render", {cfg.source});
  const raytrace::RayScene scene(cfg.description);
  nlohmann::json m = ManifestHead(cfg, "render", cfg.render.seed, versions);
  nlohmann::json views = nlohmann::json::array();
  nlohmann::json stats = nlohmann::json::array();
  raytrace::Frame scratch;
  for (size_t u = 0; u < cfg.description.units.size(); ++u) {
    nlohmann::json s;
    views.push_back(ViewJson(RenderView(cfg, scene, static_cast<int>(u), stage.staging(), cfg.description.units[u].name,
                                        progress, &s, &scratch)));
    stats.push_back(s);
  }
  nlohmann::json boards = nlohmann::json::array();
  for (const auto& b : cfg.boards) boards.push_back(BoardToJson(b));
  m["boards"] = boards;
  nlohmann::json frame = {{"id", 0}, {"views", views}};
  frame["checksums"] = FrameChecksums(stage.staging(), frame);
  m["frames"] = {frame};
  m["render_stats"] = stats;
  WriteFileAtomic(stage.staging() / "dataset.json", m.dump(2) + "\n");
  stage.Commit();
}

namespace {

// True if the board at this pose passes through nothing in `scene` (which holds everything but the board): no
// segment of its outline, nor of a grid of 5 x 5 lines across it, meets any geometry. A board drawn through the
// ground is not a pose a real board can take, and where the ground cuts its markers it makes false corners.
bool BoardClearOf(const raytrace::RayScene& scene, const BoardSpec& spec, const Rigid3d& world_from_board) {
  const double hw = 0.5 * spec.Width(), hh = 0.5 * spec.Height();
  const auto at = [&](double x, double y) { return world_from_board * Vec3d(x, y, 0); };
  constexpr int kLines = 5;
  for (int k = 0; k <= kLines + 1; ++k) {
    const double f = static_cast<double>(k) / (kLines + 1);  // 0 and 1: the outline
    const double x = -hw + 2 * hw * f, y = -hh + 2 * hh * f;
    if (scene.Occluded(at(x, -hh), at(x, hh), 0) || scene.Occluded(at(-hw, y), at(hw, y), 0)) return false;
  }
  return true;
}

}  // namespace

std::vector<Rigid3d> DrawBoardPoses(const SceneConfig& base, const DatasetOptions& o) {
  o.Check("dataset");
  const auto& units = base.description.units;
  HOVS_REQUIRE(!units.empty(), "dataset", "the scene has no unit");
  const bool stereo = o.kind == "stereo_aruco";
  HOVS_REQUIRE(!stereo || units.size() >= 2, "dataset", "a stereo dataset needs a scene with two units (it has ",
               units.size(), ")");
  const size_t n_units = stereo ? units.size() : 1;
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> U(0, 1);
  // Poses are drawn around the units' mean viewpoint, in the frame of unit 0's mirror axis.
  Vec3d centre = Vec3d::Zero();
  for (size_t u = 0; u < n_units; ++u) centre += units[u].world_from_mirror.translation / static_cast<double>(n_units);
  const auto corners = o.board.Corners();
  // The rest of the scene (without its own boards) may hide the board: the ground, boxes, the other unit.
  SceneConfig rest = base;
  rest.description.rects.clear();
  for (size_t k = 0; k < base.description.rects.size(); ++k) {
    bool is_board = false;
    for (const auto& b : base.boards) is_board |= b.rect_index == static_cast<int>(k);
    if (!is_board) rest.description.rects.push_back(base.description.rects[k]);
  }
  const raytrace::RayScene occluders(rest.description);
  std::vector<Rigid3d> poses;
  int tries = 0;
  while (static_cast<int>(poses.size()) < o.count) {
    HOVS_REQUIRE(++tries < 4000 * o.count, "dataset",
                 "cannot place the board visibly often enough; "
                 "check the distance and elevation ranges against the mirror's field of view");
    const double az = (U(rng) * 2 - 1) * M_PI;
    const double el = (o.min_elevation_deg + U(rng) * (o.max_elevation_deg - o.min_elevation_deg)) * kDeg;
    const double dist = o.min_distance + U(rng) * (o.max_distance - o.min_distance);
    const Vec3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Vec3d board_centre = centre + dist * units[0].world_from_mirror.Rotate(dir);
    // Face the viewpoints (LookAt's z, the printed face, points at them), then tilt and roll.
    Rigid3d pose = LookAt(board_centre, centre, (U(rng) * 2 - 1) * M_PI);
    const double tilt_axis = U(rng) * 2 * M_PI, tilt = U(rng) * o.max_tilt_deg * kDeg;
    pose.rotation =
        pose.rotation * QuaternionFromAngleAxis<double>(Vec3d(std::cos(tilt_axis), std::sin(tilt_axis), 0) * tilt);
    bool ok = BoardClearOf(occluders, o.board, pose);
    for (size_t u = 0; u < n_units && ok; ++u) {
      const auto& unit = units[u];
      const Rigid3d mirror_from_world = unit.world_from_mirror.Inverse();
      const Vec3d normal = pose.Rotate(Vec3d(0, 0, 1));
      size_t visible = 0;
      for (const auto& [id, xy] : corners) {
        const Vec3d Xw = pose * Vec3d(xy.x(), xy.y(), 0);
        Vec2d uv;
        Vec3d M;
        if (unit.rig.ImgFromMirror(mirror_from_world * Xw, &uv, &M) != ProjectionStatus::kOk) continue;
        const Vec3d Mw = unit.world_from_mirror * M;
        if (normal.dot(Mw - Xw) <= 0) continue;
        if (occluders.Occluded(Xw, Mw, 1e-6)) continue;
        bool inside = true;
        for (const Vec2d& off : {Vec2d(o.edge_margin_px, 0), Vec2d(-o.edge_margin_px, 0), Vec2d(0, o.edge_margin_px),
                                 Vec2d(0, -o.edge_margin_px)})
          inside = inside && unit.rig.SeesMirror(uv + off);
        visible += inside;
      }
      ok = visible >= o.min_visible_fraction * corners.size() - 1e-9;
    }
    if (ok) poses.push_back(pose);
  }
  return poses;
}

namespace {
void WriteDatasetPage(const fs::path& dir, const nlohmann::json& m);

// What makes two runs' frames interchangeable: the manifest's head and generator, the shard, the render settings.
nlohmann::json RunConfig(const nlohmann::json& m, const SceneConfig& base) {
  nlohmann::json c = m;
  c["render"] = {{"samples", base.render.samples},
                 {"ground_truth", base.render.ground_truth},
                 {"truth_channels", base.render.truth_file.GroupsText()},
                 {"truth_compression", base.render.truth_file.compression}};
  return c;
}

// Between frames of a resumable run: an interrupt (Ctrl-C, a SIGTERM from a scheduler) leaves the staging folder
// and its journal for the next `hovs dataset --resume` and ends the run with one error saying so.
void StopIfInterrupted(const std::atomic<bool>& interrupted, StagedDirectory* stage, const fs::path& out, size_t done,
                       size_t total) {
  if (!interrupted.load()) return;
  stage->KeepOnFailure();
  throw Error(out.string(), "interrupted after " + std::to_string(done) + " of " + std::to_string(total) +
                                " frames; the same command with --resume continues from there");
}
}  // namespace

void WriteCalibrationDataset(const SceneConfig& base, const DatasetOptions& o, const fs::path& out,
                             const std::map<std::string, std::string>& versions) {
  HOVS_REQUIRE(o.kind != "depth_sequence", "dataset", "depth_sequence datasets are written by WriteDepthSequence");
  CheckOutputFolder(out, "dataset", {base.source});
  const std::vector<Rigid3d> poses = DrawBoardPoses(base, o);
  StagedDirectory stage(out, "dataset", {base.source}, false, o.resume);
  nlohmann::json m = ManifestHead(base, o.kind, o.seed, versions);
  m["generator"] = {{"count", o.count},
                    {"distance", {o.min_distance, o.max_distance}},
                    {"min_visible_fraction", o.min_visible_fraction},
                    {"elevation_deg", {o.min_elevation_deg, o.max_elevation_deg}},
                    {"max_tilt_deg", o.max_tilt_deg},
                    {"edge_margin_px", o.edge_margin_px}};
  nlohmann::json frames = nlohmann::json::array();
  nlohmann::json boards = nlohmann::json::array();
  raytrace::Frame scratch;  // reused by every frame's render
  const size_t first = poses.size() * o.shard_index / o.shard_count,
               end = poses.size() * (o.shard_index + 1) / o.shard_count;
  if (o.shard_count > 1)
    m["shard"] = {{"index", o.shard_index}, {"count", o.shard_count}, {"first_frame", first}, {"end_frame", end}};
  FrameJournal journal(stage.staging(), RunConfig(m, base), stage.resumed(), out.string());
  if (o.progress && stage.resumed()) std::fprintf(stderr, "resuming: %zu whole frames kept\n", journal.kept());
  // A resumable run (--resume, as every Slurm task runs) keeps its folder on an interrupt; any other ends by the
  // signal with nothing left behind.
  std::atomic<bool> interrupted{false};
  std::optional<InterruptScope> interrupt_scope;
  if (o.resume) interrupt_scope.emplace(&interrupted);
  const ProgressLine progress("frame", poses.size(), o.progress);
  size_t rendered = 0;
  for (size_t i = first; i < end; ++i) {
    StopIfInterrupted(interrupted, &stage, out, i - first, end - first);
    SceneConfig cfg = base;
    // Replace the scene's boards by the calibration board at this pose.
    std::vector<raytrace::Rect> rects;
    for (size_t k = 0; k < cfg.description.rects.size(); ++k) {
      bool is_board = false;
      for (const auto& b : cfg.boards) is_board |= b.rect_index == static_cast<int>(k);
      if (!is_board) rects.push_back(cfg.description.rects[k]);
    }
    cfg.description.rects = rects;
    cfg.boards.clear();
    BoardInstance b;
    b.name = o.kind == "stereo_aruco" ? "aruco_board" : "calibration_board";
    b.object_id = raytrace::kFirstObjectId + static_cast<int>(cfg.description.objects.size());
    b.spec = o.board;
    b.world_from_board = poses[i];
    b.rect_index = static_cast<int>(cfg.description.rects.size());
    cfg.description.rects.push_back(MakeBoardRect(b.spec, b.world_from_board, b.object_id));
    cfg.description.objects.push_back({b.object_id, b.name, "board"});
    cfg.boards.push_back(b);
    // The manifest's board is frame 0's, whichever shard this is (the shards' manifests agree).
    if (i == first) {
      BoardInstance b0 = b;
      b0.world_from_board = poses[0];
      boards.push_back(BoardToJson(b0));
    }
    if (auto kept = journal.Kept(static_cast<int64_t>(i))) {  // written whole by the run this one resumes
      frames.push_back(*kept);
      continue;
    }
    const raytrace::RayScene scene(cfg.description);
    progress.Step(i + 1, rendered++, end - i);
    const size_t n_units = o.kind == "stereo_aruco" ? cfg.description.units.size() : 1;
    nlohmann::json views = nlohmann::json::array();
    double seconds = 0;
    uint64_t rays = 0;
    for (size_t u = 0; u < n_units; ++u) {
      char stem[96];
      std::snprintf(stem, sizeof stem, "%s_%04zu", cfg.description.units[u].name.c_str(), i);
      nlohmann::json stats;
      views.push_back(
          ViewJson(RenderView(cfg, scene, static_cast<int>(u), stage.staging(), stem, o.progress, &stats, &scratch)));
      seconds += stats["seconds"].get<double>();
      rays += stats["rays"].get<uint64_t>();
    }
    nlohmann::json entry = {{"id", i},
                            {"views", views},
                            {"world_from_board", PoseToJson(poses[i])},
                            {"render_seconds", seconds},
                            {"rays", rays}};
    journal.Record(&entry);
    frames.push_back(entry);
  }
  journal.Finish();
  m["boards"] = boards;
  m["frames"] = frames;
  m["generator"]["samples"] = base.render.samples;
  m["generator"]["ground_truth"] = base.render.ground_truth;
  m["generator"]["truth_channels"] = base.render.truth_file.GroupsText();
  m["generator"]["truth_compression"] = base.render.truth_file.compression;
  WriteFileAtomic(stage.staging() / "dataset.json", m.dump(2) + "\n");
  WriteDatasetPage(stage.staging(), m);
  stage.Commit();
}

namespace {

// The report page of a board dataset folder: thumbnails and the per-frame facts.
void WriteDatasetPage(const fs::path& dir, const nlohmann::json& m) {
  const auto& frames = m["frames"];
  const auto& gen = m["generator"];
  const std::string kind = m["kind"];
  // (Sets written before the channels were selectable hold all twelve.)
  const std::string channels = gen.value("truth_channels", std::string("Z,P,N,id,mask,M"));
  results::HtmlPage page("hovs dataset: " + m["name"].get<std::string>() + " (" + kind + ")");
  if (kind == "depth_sequence")
    page.Paragraph(std::to_string(frames.size()) + " frames, the rig moving " +
                   FormatNumber("%g", gen["step_m"].get<double>()) + " m per frame (heading " +
                   FormatNumber("%g", gen["heading_deg"].get<double>()) + " deg, yaw step " +
                   FormatNumber("%g", gen["yaw_step_deg"].get<double>()) +
                   " deg); every unit rendered per frame with ground truth "
                   "(truth/*.exr: " +
                   channels + "; truth/*.json: the rig of that frame).");
  else
    page.Paragraph(std::to_string(frames.size()) + " frames (" + kind + "), board poses drawn with seed " +
                   std::to_string(m["seed"].get<uint64_t>()) +
                   " so that every corner is visible; "
                   "render seed " +
                   std::to_string(m["render_seed"].get<uint64_t>()) + ", " + std::to_string(gen["samples"].get<int>()) +
                   " samples per pixel. " +
                   (gen["ground_truth"].get<bool>() ? "Ground truth per frame: truth/*.exr (channels " + channels +
                                                          ") and truth/*.json (rig, board pose, exact corner pixels)."
                                                    : "Rendered without ground truth (render.ground_truth: false)."));
  if (m.contains("shard"))
    page.Paragraph("Shard " + std::to_string(m["shard"]["index"].get<int>()) + " of " +
                   std::to_string(m["shard"]["count"].get<int>()) + " (hovs merge joins the shards).");
  std::vector<std::vector<std::string>> rows;
  for (const auto& fr : frames) {
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.2f", fr["render_seconds"].get<double>());
    for (const auto& view : fr["views"]) {
      const std::string thumb = Thumbnail(dir, view["image"].get<std::string>(), 320);
      page.Figure(thumb, "frame " + std::to_string(fr["id"].get<int>()) + ", " + view["unit"].get<std::string>(), 320);
      // (A set rendered without ground truth has no sidecar to count its corners from.)
      std::string visible = "no ground truth";
      if (view.contains("ground_truth")) {
        const auto side = nlohmann::json::parse(ReadFile(dir / view["ground_truth"]["sidecar"].get<std::string>()));
        visible = side.contains("boards") && !side["boards"].empty()
                      ? std::to_string(side["boards"][0]["visible_corners"].get<int>()) + " / " +
                            std::to_string(side["boards"][0]["corners"].size())
                      : "no board";
      }
      rows.push_back({std::to_string(fr["id"].get<int>()), view["unit"].get<std::string>(),
                      view["image"].get<std::string>(), visible, secs});
    }
  }
  page.Table({"frame", "unit", "image", "visible corners", "render of the frame (s)"}, rows);
  page.Heading("Manifest");
  page.Paragraph(
      "dataset.json lists frames, images, ground truth and the rig; real captures use the same "
      "manifest without ground truth.");
  WriteFileAtomic(dir / "index.html", page.Render());
}

}  // namespace

void MergeDatasetShards(const std::vector<fs::path>& shards, const fs::path& out) {
  HOVS_REQUIRE(!shards.empty(), "merge", "no shards given");
  std::vector<nlohmann::json> manifests;
  std::vector<fs::path> inputs;
  for (const auto& dir : shards) {
    const fs::path file = dir / "dataset.json";
    HOVS_REQUIRE(fs::is_regular_file(file), dir.string(), "not a dataset folder (no dataset.json)");
    manifests.push_back(LoadDatasetManifest(file));
    inputs.push_back(file);
  }
  // Everything but the frames and the shard record must agree: config, seed, kind, units, versions, board.
  const std::vector<size_t> order = OrderShards(manifests, inputs, {"frames"});
  nlohmann::json merged = manifests[order[0]];
  merged.erase("shard");
  merged.erase("frames");
  const int frames =
      static_cast<int>(JsonInteger(merged["generator"], "count", 1, 1000000, inputs[0].string() + " (generator)"));
  CheckOutputFolder(out, "merge", inputs);
  StagedDirectory stage(out, "merge", inputs);
  merged["frames"] = nlohmann::json::array();
  for (const size_t k : order) {
    const fs::path dir = shards[k];
    for (const auto& fr : manifests[k]["frames"]) {
      HOVS_REQUIRE(fr["id"].get<int64_t>() == static_cast<int64_t>(merged["frames"].size()), inputs[k].string(),
                   "frame ", fr["id"].dump(), " is out of order (expected ", merged["frames"].size(), ")");
      HOVS_REQUIRE(fr.contains("checksums"), inputs[k].string(), "frame ", fr["id"].dump(),
                   " has no checksums: a shard is merged only when every file can be verified");
      for (const auto& view : fr["views"]) {
        std::vector<std::string> files = {view["image"].get<std::string>()};
        if (view.contains("ground_truth"))
          for (const char* key : {"exr", "sidecar"})
            if (view["ground_truth"].contains(key)) files.push_back(view["ground_truth"][key]);
        // Every file as its shard recorded it (LoadDatasetManifest expects the checksums). The shard's thumbnails
        // carry no checksum, so they are not taken: the merged page makes its own from the verified images (the
        // bytes one process writes).
        for (const auto& f : files) {
          HOVS_REQUIRE(fs::is_regular_file(dir / f), (dir / f).string(), "is missing from its shard");
          VerifyExpectedChecksum(dir / f);
        }
        for (const auto& f : files) {
          fs::create_directories((stage.staging() / f).parent_path());
          // A hard link where the file system allows (a merged set of hundreds of GB is not copied), else a copy.
          std::error_code ec;
          fs::create_hard_link(dir / f, stage.staging() / f, ec);
          if (ec) fs::copy_file(dir / f, stage.staging() / f);
        }
      }
      merged["frames"].push_back(fr);
    }
  }
  HOVS_REQUIRE(static_cast<int>(merged["frames"].size()) == frames, "merge", "the shards hold ",
               merged["frames"].size(), " frames but the set has ", frames);
  WriteFileAtomic(stage.staging() / "dataset.json", merged.dump(2) + "\n");
  WriteDatasetPage(stage.staging(), merged);
  stage.Commit();
}

Rigid3d WorldFromRigAt(const SceneConfig& base, const DatasetOptions& o, int frame) {
  Vec3d centroid = Vec3d::Zero();
  for (const auto& u : base.description.units) centroid += u.world_from_mirror.translation;
  centroid /= std::max<size_t>(1, base.description.units.size());
  const double h = o.heading_deg * kDeg, yaw = frame * o.yaw_step_deg * kDeg;
  const Vec3d move = frame * o.step_m * Vec3d(std::cos(h), std::sin(h), 0);
  const Rigid3d turn(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Vec3d::UnitZ())), Vec3d::Zero());
  return Rigid3d::Translation(centroid + move) * turn * Rigid3d::Translation(-centroid);
}

void WriteDepthSequence(const SceneConfig& base, const DatasetOptions& o, const fs::path& out,
                        const std::map<std::string, std::string>& versions) {
  o.Check("dataset");
  HOVS_REQUIRE(o.kind == "depth_sequence", "dataset", "WriteDepthSequence needs kind depth_sequence");
  HOVS_REQUIRE(!base.description.units.empty(), base.source, "the scene has no catadioptric unit");
  CheckOutputFolder(out, "dataset", {base.source});
  // The whole path first: a rig driven into an object is refused before anything is rendered.
  const UnitClearance clearance(base.description);
  for (int i = 0; i < o.count; ++i)
    for (raytrace::CatadioptricUnit u : base.description.units) {
      u.world_from_mirror = WorldFromRigAt(base, o, i) * u.world_from_mirror;
      clearance.Check(u, "depth_sequence frame " + std::to_string(i));
    }
  StagedDirectory stage(out, "dataset", {base.source}, false, o.resume);
  nlohmann::json m = ManifestHead(base, o.kind, o.seed, versions);
  m["generator"] = {{"count", o.count},
                    {"step_m", o.step_m},
                    {"heading_deg", o.heading_deg},
                    {"yaw_step_deg", o.yaw_step_deg},
                    {"note", "units in 'units' are at frame 0; frame k's units are world_from_rig(k) * them"}};
  nlohmann::json boards = nlohmann::json::array();
  for (const auto& b : base.boards) boards.push_back(BoardToJson(b));
  m["boards"] = boards;
  nlohmann::json frames = nlohmann::json::array();
  raytrace::Frame scratch;  // reused by every frame's render
  const int first = o.count * o.shard_index / o.shard_count, end = o.count * (o.shard_index + 1) / o.shard_count;
  if (o.shard_count > 1)
    m["shard"] = {{"index", o.shard_index}, {"count", o.shard_count}, {"first_frame", first}, {"end_frame", end}};
  FrameJournal journal(stage.staging(), RunConfig(m, base), stage.resumed(), out.string());
  if (o.progress && stage.resumed()) std::fprintf(stderr, "resuming: %zu whole frames kept\n", journal.kept());
  // A resumable run (--resume, as every Slurm task runs) keeps its folder on an interrupt; any other ends by the
  // signal with nothing left behind.
  std::atomic<bool> interrupted{false};
  std::optional<InterruptScope> interrupt_scope;
  if (o.resume) interrupt_scope.emplace(&interrupted);
  const ProgressLine progress("frame", static_cast<size_t>(o.count), o.progress);
  size_t rendered = 0;
  for (int i = first; i < end; ++i) {
    StopIfInterrupted(interrupted, &stage, out, static_cast<size_t>(i - first), static_cast<size_t>(end - first));
    if (auto kept = journal.Kept(i)) {  // written whole by the run this one resumes
      frames.push_back(*kept);
      continue;
    }
    SceneConfig cfg = base;
    const Rigid3d world_from_rig = WorldFromRigAt(base, o, i);
    for (auto& u : cfg.description.units) u.world_from_mirror = world_from_rig * u.world_from_mirror;
    const raytrace::RayScene scene(cfg.description);
    progress.Step(static_cast<size_t>(i + 1), rendered++, static_cast<size_t>(end - i));
    nlohmann::json views = nlohmann::json::array();
    double seconds = 0;
    for (size_t u = 0; u < cfg.description.units.size(); ++u) {
      char stem[96];
      std::snprintf(stem, sizeof stem, "%s_%04d", cfg.description.units[u].name.c_str(), i);
      nlohmann::json stats;
      views.push_back(
          ViewJson(RenderView(cfg, scene, static_cast<int>(u), stage.staging(), stem, o.progress, &stats, &scratch)));
      seconds += stats["seconds"].get<double>();
    }
    nlohmann::json entry = {
        {"id", i}, {"views", views}, {"world_from_rig", PoseToJson(world_from_rig)}, {"render_seconds", seconds}};
    journal.Record(&entry);
    frames.push_back(entry);
  }
  journal.Finish();
  m["frames"] = frames;
  m["generator"]["samples"] = base.render.samples;
  m["generator"]["ground_truth"] = base.render.ground_truth;
  m["generator"]["truth_channels"] = base.render.truth_file.GroupsText();
  m["generator"]["truth_compression"] = base.render.truth_file.compression;
  WriteFileAtomic(stage.staging() / "dataset.json", m.dump(2) + "\n");
  WriteDatasetPage(stage.staging(), m);
  stage.Commit();
}

}  // namespace hovs::scenes
