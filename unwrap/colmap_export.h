// COLMAP's text model (cameras.txt, images.txt, points3D.txt, as COLMAP's documentation of its output format
// describes them) for the perspective views of a remap table, so that COLMAP reconstructs from hovs' views with
// known cameras (point_triangulator with known poses, or the mapper with fixed intrinsics).
//
//   cameras.txt   one PINHOLE camera per perspective view: width, height, fx, fy, cx + 0.5, cy + 0.5 (COLMAP puts
//                 the top-left pixel's centre at (0.5, 0.5), hovs at (0, 0))
//   images.txt    one image per frame and view, named <frame>/<view>.png (the files hovs unwrap writes), with
//                 cam_from_world = (world_from_mirror * mirror_from_view)^-1 as QW QX QY QZ TX TY TZ; the view
//                 frame is COLMAP's camera frame (x right, y down, z forward); an empty line of 2-D points
//   points3D.txt  empty
// Panoramas are left out: COLMAP has no cylindrical or longitude-latitude camera.
// World poses come from the frames (a rendered dataset's sidecars); without them every frame takes the unit's
// mirror frame as the world, which the files' comments say.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/rigid.h"
#include "unwrap/remap_table.h"

namespace hovs::unwrap {

struct ColmapFrame {
  std::string name;                          // the frame's folder of views
  std::optional<Rigid3d> world_from_mirror;  // the unit's pose at this frame, when known
};

struct ColmapModel {
  std::string cameras, images, points3d;  // the three files' text
  int cameras_count = 0, images_count = 0;
};

// Throws hovs::Error when the table has no perspective view or some frames have a pose and others not.
ColmapModel FormatColmapModel(const RemapTable& table, const std::vector<ColmapFrame>& frames);

}  // namespace hovs::unwrap
