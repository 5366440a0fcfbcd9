#include "scenes/dataset.h"

#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"
#include "core/io.h"
#include "raytrace/render.h"
#include "results/html.h"
#include "scenes/ground_truth.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

namespace hovs::scenes {
namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

void DatasetOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(kind == "mono_calibration", where + ".kind", "unknown dataset kind '", kind, "' (known: mono_calibration)");
  HOVS_REQUIRE(count >= 1 && count <= 10000, where + ".count", "must be in 1..10000");
  HOVS_REQUIRE(min_distance > 0 && max_distance >= min_distance, where + ".distance", "needs 0 < min <= max");
  HOVS_REQUIRE(min_elevation_deg < max_elevation_deg && max_elevation_deg < 90 && min_elevation_deg > -90,
               where + ".elevation", "needs -90 < min < max < 90 degrees");
  HOVS_REQUIRE(max_tilt_deg >= 0 && max_tilt_deg < 80, where + ".max_tilt_deg", "must be in [0, 80)");
  CheckBoard(board, where + ".board");
}

namespace {

struct ViewRecord {
  std::string unit, image, exr, sidecar;
};

// Renders unit u of the scene into dir: image, EXR ground truth, sidecar. Returns the manifest view.
ViewRecord RenderView(const SceneConfig& cfg, const raytrace::RayScene& scene, int u, const fs::path& dir,
                      const std::string& stem, bool progress, nlohmann::json* stats) {
  raytrace::RenderOptions ro = cfg.render;
  ro.progress = progress;
  const raytrace::Frame frame = raytrace::Render(scene, raytrace::ViewCamera::Unit(u), ro);
  int channels = 0;
  const std::vector<float> img = raytrace::ApplySensor(frame, ro.sensor, ro.seed ^ std::hash<std::string>{}(stem), &channels);
  const std::string unit = scene.description().units[u].name;
  ViewRecord v{unit, "images/" + stem + ".png", "", ""};
  raytrace::WriteImage(dir / v.image, frame.width, frame.height, channels, img, ro.sensor.bit_depth);
  if (ro.ground_truth) {
    v.exr = "truth/" + stem + ".exr";
    v.sidecar = "truth/" + stem + ".json";
    raytrace::WriteGroundTruthExr(dir / v.exr, frame, {{"scene", cfg.name}, {"unit", unit}, {"frame", stem},
                                                       {"world_frame", "z up, metres"}, {"sidecar", v.sidecar}});
    nlohmann::json side = FrameSidecar(cfg, scene, u);
    side["image"] = v.image;
    side["render"] = {{"samples", ro.samples}, {"seed", ro.seed}, {"bit_depth", ro.sensor.bit_depth},
                      {"bayer", ro.sensor.bayer}, {"vignetting", ro.sensor.vignetting},
                      {"full_well", ro.sensor.full_well}, {"read_noise", ro.sensor.read_noise}};
    WriteFileAtomic(dir / v.sidecar, side.dump(1) + "\n");
  }
  if (stats) {
    (*stats)["rays"] = frame.rays;
    (*stats)["seconds"] = frame.seconds;
  }
  return v;
}

// A thumbnail (longest side `size` px) of an image file, written next to it under thumbs/.
std::string Thumbnail(const fs::path& dir, const std::string& image, int size) {
  OIIO::ImageBuf src((dir / image).string());
  HOVS_REQUIRE(src.read(0, 0, true, OIIO::TypeDesc::FLOAT), image, "cannot read for the thumbnail");
  const auto& spec = src.spec();
  const double scale = static_cast<double>(size) / std::max(spec.width, spec.height);
  const int w = std::max(1, static_cast<int>(spec.width * scale)), h = std::max(1, static_cast<int>(spec.height * scale));
  OIIO::ImageBuf dst = OIIO::ImageBufAlgo::resize(src, "", 0, OIIO::ROI(0, w, 0, h, 0, 1, 0, spec.nchannels));
  const std::string rel = "thumbs/" + fs::path(image).filename().string();
  fs::create_directories(dir / "thumbs");
  const fs::path tmp = dir / "thumbs" / (".tmp-" + fs::path(image).filename().string());
  HOVS_REQUIRE(dst.write(tmp.string(), OIIO::TypeDesc::UINT8), rel, "cannot write thumbnail: ", dst.geterror());
  fs::rename(tmp, dir / rel);
  return rel;
}

nlohmann::json ViewJson(const ViewRecord& v) {
  nlohmann::json j = {{"unit", v.unit}, {"image", v.image}};
  if (!v.exr.empty()) j["ground_truth"] = {{"exr", v.exr}, {"sidecar", v.sidecar}};
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
  StagedDirectory stage(out);
  const raytrace::RayScene scene(cfg.description);
  nlohmann::json m = ManifestHead(cfg, "render", cfg.render.seed, versions);
  nlohmann::json views = nlohmann::json::array();
  nlohmann::json stats = nlohmann::json::array();
  for (size_t u = 0; u < cfg.description.units.size(); ++u) {
    nlohmann::json s;
    views.push_back(ViewJson(RenderView(cfg, scene, static_cast<int>(u), stage.staging(),
                                        cfg.description.units[u].name, progress, &s)));
    stats.push_back(s);
  }
  nlohmann::json boards = nlohmann::json::array();
  for (const auto& b : cfg.boards) boards.push_back(BoardToJson(b));
  m["boards"] = boards;
  m["frames"] = {{{"id", 0}, {"views", views}}};
  m["render_stats"] = stats;
  WriteFileAtomic(stage.staging() / "dataset.json", m.dump(2) + "\n");
  stage.Commit();
}

std::vector<Rigid3d> DrawBoardPoses(const SceneConfig& base, const DatasetOptions& o) {
  o.Check("dataset");
  HOVS_REQUIRE(!base.description.units.empty(), "dataset", "the scene has no unit");
  // The board alone, over the base scene without its own boards.
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> U(0, 1);
  const auto& unit = base.description.units[0];
  const Vec3d F1 = unit.world_from_mirror.translation;
  const Rigid3d mirror_from_world = unit.world_from_mirror.Inverse();
  const auto corners = o.board.Corners();
  std::vector<Rigid3d> poses;
  int tries = 0;
  while (static_cast<int>(poses.size()) < o.count) {
    HOVS_REQUIRE(++tries < 2000 * o.count, "dataset", "cannot place the board with every corner visible; "
                 "check the distance and elevation ranges against the mirror's field of view");
    const double az = (U(rng) * 2 - 1) * M_PI;
    const double el = (o.min_elevation_deg + U(rng) * (o.max_elevation_deg - o.min_elevation_deg)) * kDeg;
    const double dist = o.min_distance + U(rng) * (o.max_distance - o.min_distance);
    const Vec3d dir_mirror(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Vec3d centre = F1 + dist * unit.world_from_mirror.Rotate(dir_mirror);
    // Face the viewpoint, then tilt about a random in-plane axis and roll.
    Rigid3d pose = LookAt(centre, F1, (U(rng) * 2 - 1) * M_PI);
    const double tilt_axis = U(rng) * 2 * M_PI, tilt = U(rng) * o.max_tilt_deg * kDeg;
    pose.rotation = pose.rotation * QuaternionFromAngleAxis<double>(Vec3d(std::cos(tilt_axis), std::sin(tilt_axis), 0) * tilt);
    // LookAt's z points at the viewpoint: the printed face (+z) faces it.
    bool ok = true;
    for (const auto& [id, xy] : corners) {
      const Vec3d X = mirror_from_world * (pose * Vec3d(xy.x(), xy.y(), 0));
      Vec2d uv;
      Vec3d M;
      if (unit.rig.ImgFromMirror(X, &uv, &M) != ProjectionStatus::kOk) {
        ok = false;
        break;
      }
      // Keep a margin inside the valid region: the pixels around must see the mirror too.
      for (const Vec2d& off : {Vec2d(o.edge_margin_px, 0), Vec2d(-o.edge_margin_px, 0), Vec2d(0, o.edge_margin_px),
                               Vec2d(0, -o.edge_margin_px)})
        if (!unit.rig.SeesMirror(uv + off)) ok = false;
      if (!ok) break;
    }
    if (ok) poses.push_back(pose);
  }
  return poses;
}

void WriteCalibrationDataset(const SceneConfig& base, const DatasetOptions& o, const fs::path& out,
                             const std::map<std::string, std::string>& versions) {
  const std::vector<Rigid3d> poses = DrawBoardPoses(base, o);
  StagedDirectory stage(out);
  nlohmann::json m = ManifestHead(base, o.kind, o.seed, versions);
  m["generator"] = {{"count", o.count}, {"distance", {o.min_distance, o.max_distance}},
                    {"elevation_deg", {o.min_elevation_deg, o.max_elevation_deg}}, {"max_tilt_deg", o.max_tilt_deg},
                    {"edge_margin_px", o.edge_margin_px}};
  nlohmann::json frames = nlohmann::json::array();
  nlohmann::json boards = nlohmann::json::array();
  for (size_t i = 0; i < poses.size(); ++i) {
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
    b.name = "calibration_board";
    b.object_id = raytrace::kFirstObjectId + static_cast<int>(cfg.description.objects.size());
    b.spec = o.board;
    b.world_from_board = poses[i];
    b.rect_index = static_cast<int>(cfg.description.rects.size());
    cfg.description.rects.push_back(MakeBoardRect(b.spec, b.world_from_board, b.object_id));
    cfg.description.objects.push_back({b.object_id, b.name, "board"});
    cfg.boards.push_back(b);
    const raytrace::RayScene scene(cfg.description);
    char stem[64];
    std::snprintf(stem, sizeof stem, "%s_%04zu", cfg.description.units[0].name.c_str(), i);
    if (o.progress) std::fprintf(stderr, "frame %zu/%zu\n", i + 1, poses.size());
    nlohmann::json stats;
    const ViewRecord v = RenderView(cfg, scene, 0, stage.staging(), stem, o.progress, &stats);
    frames.push_back({{"id", i}, {"views", {ViewJson(v)}}, {"world_from_board", PoseToJson(poses[i])},
                      {"render_seconds", stats["seconds"]}, {"rays", stats["rays"]}});
    if (i == 0) boards.push_back(BoardToJson(b));
  }
  m["boards"] = boards;
  m["frames"] = frames;
  WriteFileAtomic(stage.staging() / "dataset.json", m.dump(2) + "\n");

  // A report page: thumbnails and the per-frame facts.
  results::HtmlPage page("hovs dataset: " + base.name + " (" + o.kind + ")");
  page.Paragraph(std::to_string(frames.size()) + " frames of unit " + base.description.units[0].name +
                 ", board poses drawn with seed " + std::to_string(o.seed) + " so that every corner is visible; "
                 "render seed " + std::to_string(base.render.seed) + ", " + std::to_string(base.render.samples) +
                 " samples per pixel. Ground truth per frame: truth/*.exr (channels Z, P, N, id, mask, M) and "
                 "truth/*.json (rig, board pose, exact corner pixels).");
  std::vector<std::vector<std::string>> rows;
  for (const auto& fr : frames) {
    const auto& view = fr["views"][0];
    const std::string thumb = Thumbnail(stage.staging(), view["image"].get<std::string>(), 320);
    page.Figure(thumb, "frame " + std::to_string(fr["id"].get<int>()), 320);
    const auto side = nlohmann::json::parse(ReadFile(stage.staging() / view["ground_truth"]["sidecar"].get<std::string>()));
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.2f", fr["render_seconds"].get<double>());
    rows.push_back({std::to_string(fr["id"].get<int>()), view["image"].get<std::string>(),
                    std::to_string(side["boards"][0]["visible_corners"].get<int>()), secs});
  }
  page.Table({"frame", "image", "visible corners", "render (s)"}, rows);
  page.Heading("Manifest");
  page.Paragraph("dataset.json lists frames, images, ground truth and the rig; real captures use the same "
                 "manifest without ground truth.");
  WriteFileAtomic(stage.staging() / "index.html", page.Render());
  stage.Commit();
}

}  // namespace hovs::scenes
