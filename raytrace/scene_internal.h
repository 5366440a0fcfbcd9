// What the scene's files share and its users do not see: the analytic shapes (mirror, mount ring, lens face) as
// Embree user geometry, the Embree masks that keep a ray off the shapes it cannot meet, a batch's Embree lanes and
// the packet set-up. scene.cc builds the scene, user_geometry.cc holds Embree's callbacks, scene_intersect.cc
// intersects rays and batches, shading.cc turns hits into colours and ground truth.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "raytrace/scene.h"

namespace hovs::raytrace {

// Analytic shapes as Embree user geometry. Intersections run in double in the shape's own frame.
// Embree hands the callbacks rays in the frame of the scene the geometry is attached to: the world, or for the
// parts of a moving unit (attached to a scene instanced with the unit's motion) the unit's mirror frame.
struct RayScene::UserGeometry {
  enum class Kind { kMirror, kAnnulus } kind = Kind::kMirror;
  int object_id = kMirrorId;
  int unit = -1;
  Rigid3d world_from_local, local_from_world;  // at time 0
  // The callbacks' frame from the local one: world_from_local, or mirror_from_local for a moving unit's part.
  Rigid3d ray_from_local;
  HyperboloidMirror<double> mirror;  // kMirror: local frame = mirror frame
  double r_inner = 0, r_outer = 0;   // kAnnulus: disc in local z = 0
  Rgb colour = {0, 0, 0}, back_colour = {0, 0, 0};
  // The transforms as matrices (a quaternion rotation costs twice a matrix product): set by Prepare().
  Eigen::Matrix3d R_local_from_world, R_world_from_local;
  Vec3d t_local_from_world;
  Eigen::Matrix3d R_local_from_ray, R_ray_from_local;
  Vec3d t_local_from_ray;
  void Prepare(bool instanced) {
    R_local_from_world = local_from_world.rotation.toRotationMatrix();
    R_world_from_local = world_from_local.rotation.toRotationMatrix();
    t_local_from_world = local_from_world.translation;
    if (!instanced) {  // the callbacks' rays are world rays: the same matrices, to the bit
      ray_from_local = world_from_local;
      R_local_from_ray = R_local_from_world, R_ray_from_local = R_world_from_local;
      t_local_from_ray = t_local_from_world;
      return;
    }
    const Rigid3d local_from_ray = ray_from_local.Inverse();
    R_local_from_ray = local_from_ray.rotation.toRotationMatrix();
    R_ray_from_local = ray_from_local.rotation.toRotationMatrix();
    t_local_from_ray = local_from_ray.translation;
  }

  // Ray in world coordinates (the unit at time 0); t along the given (not necessarily unit) direction.
  bool Intersect(const Vec3d& o_w, const Vec3d& d_w, double tnear, double tfar, double* t, Vec3d* n_w) const {
    return IntersectLocal(R_local_from_world * o_w + t_local_from_world, R_local_from_world * d_w, tnear, tfar, t, n_w,
                          R_world_from_local);
  }
  // Ray in the callbacks' frame; the normal in that frame.
  bool IntersectInRayFrame(const Vec3d& o_r, const Vec3d& d_r, double tnear, double tfar, double* t, Vec3d* n_r) const {
    return IntersectLocal(R_local_from_ray * o_r + t_local_from_ray, R_local_from_ray * d_r, tnear, tfar, t, n_r,
                          R_ray_from_local);
  }
  // Ray in the local frame; the normal rotated by R_out_from_local.
  bool IntersectLocal(const Vec3d& o, const Vec3d& d, double tnear, double tfar, double* t, Vec3d* n_out,
                      const Eigen::Matrix3d& R_out_from_local) const {
    if (kind == Kind::kMirror) {
      double tt = 0;
      if (!mirror.IntersectSheet(o, d, &tt, tnear) || !(tt < tfar)) return false;
      const Vec3d p = o + tt * d;
      if (!mirror.WithinRim(p)) return false;
      *t = tt;
      if (n_out) *n_out = R_out_from_local * mirror.Normal(p);
      return true;
    }
    if (d.z() == 0) return false;
    const double tt = -o.z() / d.z();
    if (!(tt > tnear && tt < tfar)) return false;
    const Vec3d p = o + tt * d;
    const double r2 = p.x() * p.x() + p.y() * p.y();
    if (r2 < r_inner * r_inner || r2 > r_outer * r_outer) return false;
    *t = tt;
    if (n_out) *n_out = R_out_from_local.col(2);
    return true;
  }

  // The shape's bounding box in the frame of frame_from_local (the callbacks' frame, or the world at time 0).
  void Bounds(const Rigid3d& frame_from_local, RTCBounds* b) const {
    Vec3d lo_l, hi_l;
    if (kind == Kind::kMirror) {
      const double R = mirror.RimRadius();
      lo_l = Vec3d(-R, -R, mirror.VertexZ());
      hi_l = Vec3d(R, R, mirror.RimZ());
    } else {
      lo_l = Vec3d(-r_outer, -r_outer, 0);
      hi_l = Vec3d(r_outer, r_outer, 0);
    }
    Vec3d lo = Vec3d::Constant(HUGE_VAL), hi = Vec3d::Constant(-HUGE_VAL);
    for (int k = 0; k < 8; ++k) {
      const Vec3d c((k & 1) ? hi_l.x() : lo_l.x(), (k & 2) ? hi_l.y() : lo_l.y(), (k & 4) ? hi_l.z() : lo_l.z());
      const Vec3d w = frame_from_local * c;
      lo = lo.cwiseMin(w), hi = hi.cwiseMax(w);
    }
    const double pad = 1e-6;
    b->lower_x = static_cast<float>(lo.x() - pad), b->lower_y = static_cast<float>(lo.y() - pad);
    b->lower_z = static_cast<float>(lo.z() - pad);
    b->upper_x = static_cast<float>(hi.x() + pad), b->upper_y = static_cast<float>(hi.y() + pad);
    b->upper_z = static_cast<float>(hi.z() + pad);
  }
};

namespace internal {

// Embree masks: for units 0..9, unit u's mirror has bit 1 + 3u, its lens face bit 2 + 3u and its mount ring bit
// 3 + 3u; every other geometry (and those of units from 10 on) has bit 0. A ray leaving unit u's mirror clears
// the mirror's bit; a ray leaving unit u's camera straight (it missed the mirror within the rim, so it cannot
// meet it, and it starts on the lens face) clears both. Embree then does not even call those callbacks. Units
// from 10 on share bit 0 (LaneRay's id test stays).
inline constexpr int kMaskUnits = 10;
inline unsigned MirrorMaskBit(int unit) { return unit >= 0 && unit < kMaskUnits ? 1u << (1 + 3 * unit) : 1u; }
inline unsigned LensMaskBit(int unit) { return unit >= 0 && unit < kMaskUnits ? 1u << (2 + 3 * unit) : 1u; }
inline unsigned MountMaskBit(int unit) { return unit >= 0 && unit < kMaskUnits ? 1u << (3 + 3 * unit) : 1u; }
inline unsigned RayMask(int from_mirror, int from_camera = -1) {
  // Selects, not branches (this runs for every ray).
  const unsigned fm = static_cast<unsigned>(from_mirror), fc = static_cast<unsigned>(from_camera);
  const unsigned clear_m = fm < kMaskUnits ? 1u << (1 + 3 * fm) : 0u;
  const unsigned clear_c = fc < kMaskUnits ? 3u << (1 + 3 * fc) : 0u;  // the mirror's and the lens face's bits
  return ~(clear_m | clear_c);
}

// Embree's callbacks for the analytic shapes (user_geometry.cc).
void UserBounds(const RTCBoundsFunctionArguments* args);
void UserIntersect(const RTCIntersectFunctionNArguments* args);
void UserOccluded(const RTCOccludedFunctionNArguments* args);

// Half the width of a unit's camera body (a square box behind the lens face, within the lens face's disc).
inline double BodyHalfWidth(const CatadioptricUnit& u) { return 0.7 * u.rig.occluder_radius; }

// Radius of the mount ring that hides everything the camera sees past the rim.
inline double DefaultMountRadius(const CatadioptricUnit& u) {
  const auto& cam = u.rig.camera;
  const double half_w = 0.5 * cam.width / cam.fx, half_h = 0.5 * cam.height / cam.fy;
  const double tan_diag = std::hypot(half_w, half_h);
  const double height = u.rig.mirror.RimZ() + 2 * u.rig.mirror.c();
  return std::max(u.rig.mirror.RimRadius() + 0.015, 1.1 * height * tan_diag + 0.01);
}

// Lane i of a packet, everything but origin and direction: tnear, an infinite tfar, the Embree mask of the
// ray's origin (see RayMask), and the id, which carries the unit whose (convex) mirror the ray leaves (the
// mirror callback skips it; -1: none).
template <class RayHitW>
void SetLane(RayHitW* rh, int i, float tnear, int from_mirror, int from_camera) {
  rh->ray.tnear[i] = tnear;
  rh->ray.tfar[i] = std::numeric_limits<float>::infinity();
  rh->ray.mask[i] = RayMask(from_mirror, from_camera), rh->ray.flags[i] = 0, rh->ray.time[i] = 0;
  rh->ray.id[i] = static_cast<unsigned>(std::max(from_mirror, -1) + 1);
  rh->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

// Traces a filled packet (rtcIntersect8 or rtcIntersect16), rays flagged coherent.
template <class RayHitW, class IntersectW>
void TracePacket(RTCScene scene, const int* valid, RayHitW* rh, IntersectW intersect) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  intersect(valid, scene, &ctx, rh);
}

}  // namespace internal

// The Embree lanes of a whole batch, set up once before its packets are traced.
//
// A unit's straight camera rays (they missed its mirror within the rim: 40 % of a frame's samples, the image
// past the rim) end on its mount ring unless something lies in between. They meet the ring analytically, in
// double (RayBatch::mount_t, from the renderer's ray set-up in the mirror frame where the rim test was made, or
// here with the ring's own test), and go to Embree only up to that distance with the ring masked off: anything
// nearer still wins, and the ring's callback is not called for them. Where nothing can be in between
// (OwnMount::path_clear) they do not go to Embree at all; a packet of such rays only gets its hits.
struct BatchLanes {
  alignas(64) int valid[RayBatch::kMax];            // -1: traced by Embree, 0: not
  alignas(64) float tfar[RayBatch::kMax];           // > 0: traced only up to here (the ring's distance)
  alignas(64) unsigned mask_off[RayBatch::kMax];    // Embree mask bits cleared (the ring's)
  alignas(64) unsigned mount_geom[RayBatch::kMax];  // the ring that ends the ray where Embree finds nothing, or
                                                    // RTC_INVALID_GEOMETRY_ID
};

}  // namespace hovs::raytrace
