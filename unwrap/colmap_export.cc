#include "unwrap/colmap_export.h"

#include <cstdio>

#include "core/error.h"

namespace hovs::unwrap {

namespace {

std::string Numbers(std::initializer_list<double> values) {
  std::string out;
  char buf[40];
  for (double v : values) {
    std::snprintf(buf, sizeof buf, " %.17g", v);
    out += buf;
  }
  return out;
}

}  // namespace

ColmapModel FormatColmapModel(const RemapTable& table, const std::vector<ColmapFrame>& frames) {
  std::vector<int> views;
  for (int i = 0; i < static_cast<int>(table.views.size()); ++i)
    if (table.views[i].view.projection == ViewProjection::kPerspective) views.push_back(i);
  HOVS_REQUIRE(!views.empty(), "--colmap", "the layout has no perspective view (COLMAP has no panorama camera)");
  size_t with_pose = 0;
  for (const auto& f : frames) with_pose += f.world_from_mirror.has_value();
  HOVS_REQUIRE(with_pose == 0 || with_pose == frames.size(), "--colmap", "only ", with_pose, " of ", frames.size(),
               " frames have a world pose");
  ColmapModel m;
  m.cameras =
      "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# hovs unwrap: one PINHOLE camera per perspective view (principal point in COLMAP's pixel "
      "convention: hovs' + 0.5)\n# Number of cameras: " +
      std::to_string(views.size()) + "\n";
  for (size_t c = 0; c < views.size(); ++c) {
    const auto& v = table.views[views[c]].view;
    m.cameras += std::to_string(c + 1) + " PINHOLE " + std::to_string(v.width) + " " + std::to_string(v.height) +
                 Numbers({v.camera.fx, v.camera.fy, v.camera.cx + 0.5, v.camera.cy + 0.5}) + "\n";
  }
  m.cameras_count = static_cast<int>(views.size());
  m.images_count = static_cast<int>(frames.size() * views.size());
  m.images =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
  m.images += with_pose ? "# hovs unwrap: poses from the frames' ground truth (world frame of the scene)\n"
                        : "# hovs unwrap: no world pose known: every frame's world is the unit's mirror frame\n";
  m.images += "# Number of images: " + std::to_string(m.images_count) + "\n";
  int id = 0;
  for (const auto& f : frames) {
    const Rigid3d world_from_mirror = f.world_from_mirror.value_or(Rigid3d());
    for (size_t c = 0; c < views.size(); ++c) {
      const auto& vt = table.views[views[c]];
      const Rigid3d cam_from_world = (world_from_mirror * Rigid3d(vt.view.mirror_from_view, Vec3d::Zero())).Inverse();
      const Eigen::Quaterniond q = cam_from_world.rotation.normalized();
      const Vec3d& t = cam_from_world.translation;
      m.images += std::to_string(++id) + Numbers({q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()}) + " " +
                  std::to_string(c + 1) + " " + f.name + "/" + vt.spec.name + ".png\n\n";
    }
  }
  m.points3d =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 0, mean track length: 0\n";
  return m;
}

}  // namespace hovs::unwrap
