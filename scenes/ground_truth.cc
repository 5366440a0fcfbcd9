#include "scenes/ground_truth.h"

#include <set>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/manifest.h"
#include "raytrace/render.h"

namespace hovs::scenes {

std::vector<CornerTruth> BoardCornerTruth(const raytrace::RayScene& scene, const BoardInstance& board, int unit) {
  const auto& units = scene.description().units;
  HOVS_REQUIRE(unit >= 0 && unit < static_cast<int>(units.size()), "ground truth", "no unit ", unit);
  const raytrace::CatadioptricUnit& u = units[unit];
  const Rigid3d mirror_from_world = u.world_from_mirror.Inverse();
  const Vec3d normal = board.world_from_board.Rotate(Vec3d(0, 0, 1));
  std::vector<CornerTruth> out;
  for (const auto& [id, xy] : board.spec.Corners()) {
    CornerTruth c;
    c.id = id;
    c.board_xy = xy;
    c.world = board.world_from_board * Vec3d(xy.x(), xy.y(), 0);
    const Vec3d X = mirror_from_world * c.world;
    Vec2d uv;
    Vec3d M;
    const ProjectionStatus s = u.rig.ImgFromMirror(X, &uv, &M);
    if (s != ProjectionStatus::kOk) {
      c.status = ToString(s);
      out.push_back(c);
      continue;
    }
    c.pixel = uv;
    c.mirror_point = M;
    const Vec3d M_world = u.world_from_mirror * M;
    if (normal.dot(M_world - c.world) <= 0) {
      c.status = "facing_away";
    } else if (scene.Occluded(c.world, M_world, 1e-6)) {
      c.status = "occluded";
    } else {
      c.status = "visible";
    }
    out.push_back(c);
  }
  return out;
}

nlohmann::json PoseToJson(const Rigid3d& p) {
  return {{"q", {p.rotation.w(), p.rotation.x(), p.rotation.y(), p.rotation.z()}},
          {"t", {p.translation.x(), p.translation.y(), p.translation.z()}}};
}

Rigid3d PoseFromJson(const nlohmann::json& j, const std::string& where) {
  const std::vector<double> qv = JsonNumbers(j, "q", 4, 4, where), tv = JsonNumbers(j, "t", 3, 3, where);
  const Eigen::Quaterniond q(qv[0], qv[1], qv[2], qv[3]);
  HOVS_REQUIRE(std::abs(q.norm() - 1) < 1e-6, where, "the quaternion is not unit length");
  const Vec3d t(tv[0], tv[1], tv[2]);
  HOVS_REQUIRE(t.norm() <= 1e4, where, "the translation is beyond 10 km");
  return Rigid3d(q.normalized(), t);
}

nlohmann::json UnitToJson(const raytrace::CatadioptricUnit& u) {
  const auto& c = u.rig.camera;
  return {{"name", u.name},
          {"model", "hyperboloid"},
          {"mirror", {{"a", u.rig.mirror.a}, {"b", u.rig.mirror.b}, {"rim_diameter", u.rig.mirror.rim_diameter}}},
          {"camera",
           {{"model", "pinhole_radtan"},
            {"width", c.width},
            {"height", c.height},
            {"fx", c.fx},
            {"fy", c.fy},
            {"cx", c.cx},
            {"cy", c.cy},
            {"distortion", {c.distortion.k1, c.distortion.k2, c.distortion.p1, c.distortion.p2}}}},
          {"cam_from_mirror", PoseToJson(u.rig.cam_from_mirror)},
          {"world_from_mirror", PoseToJson(u.world_from_mirror)},
          {"occluder_radius", u.rig.occluder_radius},
          {"single_viewpoint", u.rig.IsSingleViewpoint()}};
}

raytrace::CatadioptricUnit UnitFromJson(const nlohmann::json& j, const std::string& where) {
  static const std::set<std::string> kKeys = {"name",
                                              "model",
                                              "mirror",
                                              "camera",
                                              "cam_from_mirror",
                                              "world_from_mirror",
                                              "occluder_radius",
                                              "single_viewpoint"};
  HOVS_REQUIRE(j.is_object(), where, "a unit must be an object");
  for (const auto& [key, value] : j.items())
    HOVS_REQUIRE(kKeys.count(key), where, "unknown key '", key, "' in a unit description");
  try {
    raytrace::CatadioptricUnit u;
    u.name = j.at("name").get<std::string>();
    const auto& m = j.at("mirror");
    u.rig.mirror = {JsonNumber(m, "a", where + ".mirror"), JsonNumber(m, "b", where + ".mirror"),
                    JsonNumber(m, "rim_diameter", where + ".mirror")};
    const auto& c = j.at("camera");
    const std::string wc = where + ".camera";
    auto& cam = u.rig.camera;
    cam.width = static_cast<int>(JsonInteger(c, "width", 1, 65535, wc));
    cam.height = static_cast<int>(JsonInteger(c, "height", 1, 65535, wc));
    cam.fx = JsonNumber(c, "fx", wc), cam.fy = JsonNumber(c, "fy", wc);
    cam.cx = JsonNumber(c, "cx", wc), cam.cy = JsonNumber(c, "cy", wc);
    const std::vector<double> d = JsonNumbers(c, "distortion", 4, 4, wc);
    cam.distortion = {d[0], d[1], d[2], d[3]};
    u.rig.cam_from_mirror = PoseFromJson(j.at("cam_from_mirror"), where + ".cam_from_mirror");
    u.world_from_mirror = PoseFromJson(j.at("world_from_mirror"), where + ".world_from_mirror");
    u.rig.occluder_radius = JsonNumber(j, "occluder_radius", where);
    u.rig.Check(where);
    return u;
  } catch (const nlohmann::json::exception& e) { throw Error(where, std::string("bad unit description: ") + e.what()); }
}

nlohmann::json BoardToJson(const BoardInstance& b) {
  nlohmann::json j = {
      {"name", b.name},          {"object_id", b.object_id},  {"margin", b.spec.margin},
      {"width", b.spec.Width()}, {"height", b.spec.Height()}, {"world_from_board", PoseToJson(b.world_from_board)}};
  if (b.spec.kind == BoardSpec::Kind::kChecker) {
    j["type"] = "checker";
    j["squares"] = {b.spec.squares_x, b.spec.squares_y};
    j["square"] = b.spec.square;
    j["inner_corners"] = {b.spec.squares_x - 1, b.spec.squares_y - 1};
  } else if (b.spec.kind == BoardSpec::Kind::kCharuco) {
    j["type"] = "charuco";
    j["squares"] = {b.spec.squares_x, b.spec.squares_y};
    j["square"] = b.spec.square;
    j["marker_length"] = b.spec.marker_length;
    j["dictionary"] = b.spec.dictionary;
    j["inner_corners"] = {b.spec.squares_x - 1, b.spec.squares_y - 1};
  } else {
    j["type"] = "aruco";
    j["markers"] = {b.spec.markers_x, b.spec.markers_y};
    j["marker_length"] = b.spec.marker_length;
    j["separation"] = b.spec.marker_separation;
    j["dictionary"] = b.spec.dictionary;
  }
  return j;
}

nlohmann::json FrameSidecar(const SceneConfig& cfg, const raytrace::RayScene& scene, int unit) {
  nlohmann::json j;
  j["format"] = "hovs-frame-truth";
  j["version"] = 1;
  j["scene"] = cfg.name;
  j["unit"] = UnitToJson(scene.description().units.at(unit));
  nlohmann::json channels = nlohmann::json::array();
  const char* meaning[raytrace::GroundTruth::kChannels] = {
      "range (m) from the unit's viewpoint F1 to the surface seen; +inf for sky",
      "world point x (m)",
      "world point y (m)",
      "world point z (m)",
      "surface normal x (world)",
      "surface normal y (world)",
      "surface normal z (world)",
      "object id (0 sky, 1 mount, 2 camera body, 3 mirror back, 4.. scene objects)",
      "1 where the pixel sees the scene through the mirror, 0 outside the rim and on the camera's reflection",
      "mirror reflection point x (mirror frame, m)",
      "mirror reflection point y (mirror frame, m)",
      "mirror reflection point z (mirror frame, m)"};
  // The channels the frame's EXR holds (render.truth_channels; none: the frame has no EXR).
  for (int c : cfg.render.truth_file.Channels())
    channels.push_back({{"name", raytrace::GroundTruth::kNames[c]}, {"meaning", meaning[c]}});
  j["exr_channels"] = channels;
  j["pixel_convention"] = "u = column, v = row, centre of the top-left pixel at (0, 0); ground truth at pixel centres";
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& o : scene.description().objects)
    objects.push_back({{"id", o.id}, {"name", o.name}, {"type", o.type}});
  j["objects"] = objects;
  nlohmann::json boards = nlohmann::json::array();
  for (const BoardInstance& b : cfg.boards) {
    nlohmann::json bj = BoardToJson(b);
    nlohmann::json corners = nlohmann::json::array();
    int visible = 0;
    for (const CornerTruth& c : BoardCornerTruth(scene, b, unit)) {
      nlohmann::json cj = {{"id", c.id},
                           {"board", {c.board_xy.x(), c.board_xy.y()}},
                           {"world", {c.world.x(), c.world.y(), c.world.z()}},
                           {"status", c.status}};
      if (c.status == "visible") {
        cj["pixel"] = {c.pixel.x(), c.pixel.y()};
        cj["mirror_point"] = {c.mirror_point.x(), c.mirror_point.y(), c.mirror_point.z()};
        ++visible;
      }
      corners.push_back(cj);
    }
    bj["corners"] = corners;
    bj["visible_corners"] = visible;
    boards.push_back(bj);
  }
  j["boards"] = boards;
  return j;
}

std::vector<CornerTruth> VisibleSidecarCorners(const std::filesystem::path& sidecar) {
  return VisibleSidecarCorners(ReadJsonFile(sidecar), sidecar.string());
}

std::vector<CornerTruth> VisibleSidecarCorners(const nlohmann::json& side, const std::string& where) {
  try {
    std::vector<CornerTruth> out;
    std::set<int> ids;
    // The statuses BoardCornerTruth writes; a corner's id is its index on the board (as the writer lists them).
    static const std::set<std::string> kStatuses = [] {
      std::set<std::string> s = {"visible", "facing_away", "occluded"};
      for (ProjectionStatus p :
           {ProjectionStatus::kMissesMirror, ProjectionStatus::kInsideMirror, ProjectionStatus::kOccluded,
            ProjectionStatus::kBehindCamera, ProjectionStatus::kOutsideImage, ProjectionStatus::kNoSolution})
        s.insert(ToString(p));
      return s;
    }();
    const auto& corners = side.at("boards").at(0).at("corners");
    HOVS_REQUIRE(corners.is_array(), where, "the board's corners must be a list");
    const int64_t count = static_cast<int64_t>(corners.size());
    for (const auto& c : corners) {
      const std::string status = JsonText(c, "status");
      HOVS_REQUIRE(kStatuses.count(status), where, "a corner's status '", status, "' is not one hovs writes");
      const int64_t id = JsonInteger(c, "id", 0, count - 1, where);
      HOVS_REQUIRE(ids.insert(static_cast<int>(id)).second, where, "corner ", id, " appears twice");
      if (status != "visible") continue;
      CornerTruth t;
      t.id = static_cast<int>(id), t.status = "visible";
      const std::vector<double> b = JsonNumbers(c, "board", 2, 2, where), px = JsonNumbers(c, "pixel", 2, 2, where);
      t.board_xy = Vec2d(b[0], b[1]);
      t.pixel = Vec2d(px[0], px[1]);
      if (c.contains("world")) t.world = Vec3d(JsonNumbers(c, "world", 3, 3, where).data());
      if (c.contains("mirror_point")) t.mirror_point = Vec3d(JsonNumbers(c, "mirror_point", 3, 3, where).data());
      HOVS_REQUIRE(t.board_xy.allFinite() && t.pixel.allFinite() && t.board_xy.cwiseAbs().maxCoeff() <= 100 &&
                       t.pixel.cwiseAbs().maxCoeff() <= 1e6,
                   where, "corner ", t.id, " has non-finite or absurd coordinates");
      out.push_back(t);
    }
    return out;
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("not a hovs ground-truth sidecar with board corners: ") + e.what());
  }
}

std::map<std::filesystem::path, Rigid3d> ViewPosesByImage(const std::filesystem::path& manifest) {
  const nlohmann::json m = LoadDatasetManifest(manifest);
  std::map<std::filesystem::path, Rigid3d> poses;
  for (const auto& f : m["frames"])
    for (const auto& v : f["views"]) {
      if (!v.contains("ground_truth")) continue;
      const std::filesystem::path sidecar = ManifestPath(manifest, v["ground_truth"]["sidecar"]);
      const nlohmann::json side = ReadJsonFile(sidecar);
      HOVS_REQUIRE(side.is_object() && side.contains("unit"), sidecar.string(), "not a hovs ground-truth sidecar");
      poses[ManifestPath(manifest, v["image"]).lexically_normal()] =
          UnitFromJson(side["unit"], sidecar.string() + " (unit)").world_from_mirror;
    }
  return poses;
}

}  // namespace hovs::scenes
