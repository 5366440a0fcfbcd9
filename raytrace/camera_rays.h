// Camera rays: the rays a camera's samples trace, in the world. For a catadioptric unit, the pinhole (or thin-lens)
// camera rays in the mirror frame, reflected by the mirror (core's MirrorReflector, vectorised) where they meet it,
// else going on straight to the unit's mount ring; at each sample's time for a moving unit (motion blur). For a
// pinhole view, the camera's own rays. RenderInto and SampleRays (render.h) make every ray through RayMaker.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "core/hyperboloid.h"
#include "raytrace/render.h"

namespace hovs::raytrace {

// What UnitRays needs of a unit, in T: the mount ring (the annulus r0 <= r <= r1 in the plane z = zr of the
// mirror frame) and the camera centre c_m there; world_from_mirror (column-major R, t) and the camera centre c_w in
// the world.
template <class T>
struct UnitRayFrame {
  T zr = 0, r0 = 0, r1 = 0, c_m[3] = {0, 0, 0}, R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0},
    c_w[3] = {0, 0, 0};
};

// A unit's motion during the exposure (CatadioptricUnit::WorldFromMirrorAt): at time tau its world_from_mirror is
// the rotation by angle rate * tau about the unit axis (ax, ay, az) after world_from_mirror at 0, and its
// translation moves by velocity * tau.
struct UnitMotion {
  double rate = 0, axis[3] = {0, 0, 1}, velocity[3] = {0, 0, 0};
};

// How thin-lens samples past the rim are traced. own = 1: as the unit's own straight camera rays (from_camera =
// unit: RayScene masks off the unit's mirror and lens face, which they cannot meet, and ends them on the mount
// ring at mount_t, here computed in the mirror frame: the annulus r0 <= r <= r1 of the plane z = zr, where
// ring = 1); own = 0: as any ray (from_camera = -1, mount_t = -1: Embree finds what they meet).
struct LensRayRing {
  int own = 0, ring = 0;
  double zr = 0, r02 = 0, r12 = 0;
};

class RayMaker {
 public:
  RayMaker(const RayScene& scene, const ViewCamera& cam, const RenderOptions& o);
  int width() const { return width_; }
  int height() const { return height_; }
  const Vec3d& viewpoint() const { return viewpoint_; }
  // The camera whose pixels the rays leave.
  const PinholeCamera<double>& camera() const { return unit_ ? unit_->rig.camera : cam_.pinhole; }
  // True when the colour samples take MakeBatchF (single precision).
  bool single() const { return single_; }

  // MakeBatch's vectorised path in single precision, for the colour samples when single(): the same steps in
  // float (PixelRaysF, the float MirrorReflector::ReflectBatch, UnitRays on floats). Rays
  // within about 1e-7 relative of MakeBatch's (tests bound them), the precision Embree traces them in.
  void MakeBatchF(int n, const double* u, const double* v, RayBatchF* b) const;

  // The rays of n image points (n <= RayBatch::kMax) into a batch, with each ray's mirror point (mirror frame;
  // meaningful where from_mirror >= 0). lens_x, lens_y: thin-lens aperture points on the unit disc, tau: times in
  // the exposure (MakeLensBatch, MakePinholeLensBatch); both null: a pinhole at time 0, whose camera rays are
  // reflected together (MirrorReflector::ReflectBatch).
  //
  // nx, ny (with u, v still given): the points' normalised coordinates ((u - cx) / fx, (v - cy) / fy), already
  // computed (pixel centres: one division per column and per row of a tile), for a camera without distortion.
  void MakeBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y, const double* tau,
                 RayBatch* b, double* Mx, double* My, double* Mz, const double* nx = nullptr,
                 const double* ny = nullptr) const;

 private:
  // MakeBatch's thin-lens and motion-blur path for a unit's camera, vectorised (but for the undistortion): the
  // camera rays from the aperture (CameraLensRays), the mirror with an origin per ray (MirrorReflector::ReflectRays,
  // to the bit as Reflect), then the world rays at each sample's time (ThinLensWorldRays). Tests bound them against
  // the core's CamFromImg, ReflectCameraRay and WorldFromMirrorAt. The straight rays past the rim end on the unit's
  // mount ring, met in the unit's frame, as the pinhole samples' (LensRayRing).
  void MakeLensBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                     const double* tau, RayBatch* b, double* Mx, double* My, double* Mz) const;
  // A pinhole view's thin-lens samples (RenderInto gives pinhole views no motion blur): CameraLensRays mapped
  // straight to the world by world_from_cam (tests bound them against the core's CamFromImg).
  void MakePinholeLensBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                            RayBatch* b) const;
  // The thin-lens camera rays of n image points of cam (ThinLensRays; lens_x null or no lens radius: from the
  // centre), mapped by target_from_cam (R column-major, t); valid[i] = 0 where a point of a camera with lens
  // distortion cannot be undistorted (ThinLensRays then takes the undistorted normalised points as they are: unit
  // focal lengths, zero principal point).
  void CameraLensRays(const PinholeCamera<double>& cam, const double* R, const double* t, int n, const double* u,
                      const double* v, const double* lens_x, const double* lens_y, unsigned char* valid, double* ox,
                      double* oy, double* oz, double* dx, double* dy, double* dz) const;
  // True when the thin-lens aperture (the disc of radius lens_radius_ about the camera centre in the lens plane)
  // lies inside the unit's lower nappe, below the rim plane, with a margin: checked on a polygon circumscribing
  // its boundary circle (the region is convex).
  bool ApertureInLowerNappe() const;
  // The unit's ring, camera centre and world_from_mirror, rounded to F.
  template <class F>
  void SetFrame(UnitRayFrame<F>* f) const;

  const RayScene& scene_;
  const ViewCamera& cam_;
  double lens_radius_ = 0, focus_distance_ = 1;
  const CatadioptricUnit* unit_ = nullptr;
  std::optional<MirrorReflector> reflector_;  // the unit's mirror (same law as rig.ReflectCameraRay)
  Rigid3d world_from_cam_, mirror_from_cam_;
  Eigen::Matrix3d R_mirror_from_cam_ = Eigen::Matrix3d::Identity(), R_world_from_mirror_ = Eigen::Matrix3d::Identity();
  Vec3d t_mirror_from_cam_ = Vec3d::Zero(), t_world_from_mirror_ = Vec3d::Zero();
  Vec3d viewpoint_ = Vec3d::Zero();
  Eigen::Matrix3d R_world_from_cam_ = Eigen::Matrix3d::Identity();
  bool single_ = false;
  Eigen::Matrix3f R_mirror_from_cam_f_ = Eigen::Matrix3f::Identity();
  UnitMotion motion_;              // the unit's motion during the exposure
  LensRayRing lens_ring_;          // how thin-lens samples past the rim are traced
  bool mount_paths_clear_ = true;  // RayScene::MountPathClearDuring the exposure (blurred batches)
  UnitRayFrame<double> frame_d_;   // UnitRays' view of the unit, in double and in float
  UnitRayFrame<float> frame_f_;
  int width_ = 0, height_ = 0;
};

}  // namespace hovs::raytrace
