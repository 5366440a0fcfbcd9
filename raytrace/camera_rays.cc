#include "raytrace/camera_rays.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/sincos.h"
#include "core/vector_clones.h"

namespace hovs::raytrace {
namespace {

// A unit's batch of rays finished in one pass, from the camera rays v (mirror frame, unit length) and where
// on_mirror[i], their reflections (mirror point M, direction d in dx, dy, dz):
// - origins: tnear, from_mirror = unit on the mirror (else -1), from_camera = unit past it (else -1);
// - mount_t: for a camera ray past the mirror, where it meets the mount ring (the distance from c along v, as the
//   world ray is traced), 0 where it misses the ring; -1 on the mirror, and everywhere without ring_test;
// - the world rays: from M along d on the mirror, else from the camera centre along v, mapped by
//   world_from_mirror (d is replaced by the world direction).
// T: double, or float for single-precision colour samples. kMode: 0 any mix of rays on and past the mirror, 1
// every ray on the mirror (no ring test, v not read), 2 every ray past it (M and d not read); the same values
// in each.
template <class T, int kMode>
__attribute__((always_inline)) inline void UnitRaysOf(
    int n, const unsigned char* __restrict on_mirror, int unit, float tnear, int ring_test,
    const UnitRayFrame<T>* __restrict f, const T* __restrict vx, const T* __restrict vy, const T* __restrict vz,
    const T* __restrict Mx, const T* __restrict My, const T* __restrict Mz, T* __restrict dx, T* __restrict dy,
    T* __restrict dz, T* __restrict ox, T* __restrict oy, T* __restrict oz, float* __restrict tnear_out,
    int* __restrict from_mirror, int* __restrict from_camera, T* __restrict mount_t) {
  // Loaded once: a load inside a select stops if-conversion.
  const T r02 = f->r0 * f->r0, r12 = f->r1 * f->r1, dzr = f->zr - f->c_m[2], cx = f->c_m[0], cy = f->c_m[1];
  const T one = 1, zero = 0, half = static_cast<T>(0.5), near = static_cast<T>(1e-5);
  const T R0 = f->R[0], R1 = f->R[1], R2 = f->R[2], R3 = f->R[3], R4 = f->R[4], R5 = f->R[5], R6 = f->R[6],
          R7 = f->R[7], R8 = f->R[8], t0 = f->t[0], t1 = f->t[1], t2 = f->t[2];
  const T c0 = f->c_w[0], c1 = f->c_w[1], c2 = f->c_w[2];
  const T no_ring = ring_test ? zero : one;
  if (kMode == 1) {
    for (int i = 0; i < n; ++i) {
      tnear_out[i] = tnear;
      from_mirror[i] = unit;
      from_camera[i] = -1;
      mount_t[i] = -one;
      const T sx = dx[i], sy = dy[i], sz = dz[i];
      dx[i] = R0 * sx + R3 * sy + R6 * sz;
      dy[i] = R1 * sx + R4 * sy + R7 * sz;
      dz[i] = R2 * sx + R5 * sy + R8 * sz;
      ox[i] = R0 * Mx[i] + R3 * My[i] + R6 * Mz[i] + t0;
      oy[i] = R1 * Mx[i] + R4 * My[i] + R7 * Mz[i] + t1;
      oz[i] = R2 * Mx[i] + R5 * My[i] + R8 * Mz[i] + t2;
    }
    return;
  }
  if (kMode == 2) {
    for (int i = 0; i < n; ++i) {
      tnear_out[i] = tnear;
      from_mirror[i] = -1;
      from_camera[i] = unit;
      const T w = vz[i] != 0 ? vz[i] : one;
      const T t = dzr / w, px = cx + t * vx[i], py = cy + t * vy[i], r2 = px * px + py * py;
      const bool ring = vz[i] != 0 && t > near && r2 >= r02 && r2 <= r12;  // v is unit: t is the distance
      mount_t[i] = no_ring > half ? -one : ring ? t : zero;
      const T sx = vx[i], sy = vy[i], sz = vz[i];
      dx[i] = R0 * sx + R3 * sy + R6 * sz;
      dy[i] = R1 * sx + R4 * sy + R7 * sz;
      dz[i] = R2 * sx + R5 * sy + R8 * sz;
      ox[i] = c0, oy[i] = c1, oz[i] = c2;
    }
    return;
  }
  for (int i = 0; i < n; ++i) {
    // One comparison per select: GCC 12 if-converts these, not several selects on one bool.
    const T via = on_mirror[i] != 0 ? one : zero;
    tnear_out[i] = tnear;
    from_mirror[i] = via > half ? unit : -1;
    from_camera[i] = via > half ? -1 : unit;
    const T w = vz[i] != 0 ? vz[i] : one;
    const T t = dzr / w, px = cx + t * vx[i], py = cy + t * vy[i], r2 = px * px + py * py;
    const bool ring = vz[i] != 0 && t > near && r2 >= r02 && r2 <= r12;  // v is unit: t is the distance
    const T off = via + no_ring;                                         // > 0: no ring distance
    mount_t[i] = off > half ? -one : ring ? t : zero;
    const T sx = via > half ? dx[i] : vx[i], sy = via > half ? dy[i] : vy[i], sz = via > half ? dz[i] : vz[i];
    dx[i] = R0 * sx + R3 * sy + R6 * sz;
    dy[i] = R1 * sx + R4 * sy + R7 * sz;
    dz[i] = R2 * sx + R5 * sy + R8 * sz;
    const T mox = R0 * Mx[i] + R3 * My[i] + R6 * Mz[i] + t0, moy = R1 * Mx[i] + R4 * My[i] + R7 * Mz[i] + t1,
            moz = R2 * Mx[i] + R5 * My[i] + R8 * Mz[i] + t2;
    ox[i] = via > half ? mox : c0;
    oy[i] = via > half ? moy : c1;
    oz[i] = via > half ? moz : c2;
  }
}

// UnitRaysOf for a batch of which `on` rays meet the mirror.
template <class T>
HOVS_VECTOR_CLONES void UnitRays(int n, int on, const unsigned char* __restrict on_mirror, int unit, float tnear,
                                 int ring_test, const UnitRayFrame<T>* __restrict f, const T* __restrict vx,
                                 const T* __restrict vy, const T* __restrict vz, const T* __restrict Mx,
                                 const T* __restrict My, const T* __restrict Mz, T* __restrict dx, T* __restrict dy,
                                 T* __restrict dz, T* __restrict ox, T* __restrict oy, T* __restrict oz,
                                 float* __restrict tnear_out, int* __restrict from_mirror, int* __restrict from_camera,
                                 T* __restrict mount_t) {
  if (on == n) {
    UnitRaysOf<T, 1>(n, on_mirror, unit, tnear, ring_test, f, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ox, oy, oz, tnear_out,
                     from_mirror, from_camera, mount_t);
  } else if (on == 0) {
    UnitRaysOf<T, 2>(n, on_mirror, unit, tnear, ring_test, f, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ox, oy, oz, tnear_out,
                     from_mirror, from_camera, mount_t);
  } else {
    UnitRaysOf<T, 0>(n, on_mirror, unit, tnear, ring_test, f, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ox, oy, oz, tnear_out,
                     from_mirror, from_camera, mount_t);
  }
}

// R (column-major 3 x 3) times (x, y, 1) / |(x, y, 1)| for n points: unit rays.
HOVS_VECTOR_CLONES
void RotateRays(int n, const double* __restrict R, const double* __restrict x, const double* __restrict y,
                double* __restrict vx, double* __restrict vy, double* __restrict vz) {
  for (int i = 0; i < n; ++i) {
    const double s = 1.0 / std::sqrt(x[i] * x[i] + y[i] * y[i] + 1.0), sx = x[i] * s, sy = y[i] * s;
    vx[i] = R[0] * sx + R[3] * sy + R[6] * s;
    vy[i] = R[1] * sx + R[4] * sy + R[7] * s;
    vz[i] = R[2] * sx + R[5] * sy + R[8] * s;
  }
}

// The unit rays of n pixels of a camera without distortion in one pass: PinholeCamera::NormalisedFromImgBatch
// ((u - cx) / fx, (v - cy) / fy), then RotateRays (the same operations).
HOVS_VECTOR_CLONES
void PixelRays(int n, double fx, double fy, double cx, double cy, const double* __restrict R,
               const double* __restrict u, const double* __restrict v, double* __restrict vx, double* __restrict vy,
               double* __restrict vz) {
  for (int i = 0; i < n; ++i) {
    const double x = (u[i] - cx) / fx, y = (v[i] - cy) / fy;
    const double s = 1.0 / std::sqrt(x * x + y * y + 1.0), sx = x * s, sy = y * s;
    vx[i] = R[0] * sx + R[3] * sy + R[6] * s;
    vy[i] = R[1] * sx + R[4] * sy + R[7] * s;
    vz[i] = R[2] * sx + R[5] * sy + R[8] * s;
  }
}

// PixelRays in single precision for the colour samples: the pixel offsets from the principal point in double,
// then float throughout, with 1 / fx and 1 / fy as factors (x and y within a few 1e-7 relative of PixelRays').
HOVS_VECTOR_CLONES
void PixelRaysF(int n, double cx, double cy, float ifx, float ify, const float* __restrict R,
                const double* __restrict u, const double* __restrict v, float* __restrict vx, float* __restrict vy,
                float* __restrict vz) {
  for (int i = 0; i < n; ++i) {
    const float x = static_cast<float>(u[i] - cx) * ifx, y = static_cast<float>(v[i] - cy) * ify;
    const float s = 1.0f / std::sqrt(x * x + y * y + 1.0f), sx = x * s, sy = y * s;
    vx[i] = R[0] * sx + R[3] * sy + R[6] * s;
    vy[i] = R[1] * sx + R[4] * sy + R[7] * s;
    vz[i] = R[2] * sx + R[5] * sy + R[8] * s;
  }
}

// Where each ray of a batch starts: via[i] = 1 on unit's mirror (on_mirror[i]), else 0 (unit's camera, or a
// pinhole camera when unit < 0); the matching from_mirror / from_camera (-1: none) and tnear.
template <class T>
HOVS_VECTOR_CLONES void RayOrigins(int n, const unsigned char* __restrict on_mirror, int unit, float tnear,
                                   T* __restrict via, float* __restrict tnear_out, int* __restrict from_mirror,
                                   int* __restrict from_camera) {
  for (int i = 0; i < n; ++i) {
    const bool m = on_mirror[i] != 0;
    via[i] = m ? T(1) : T(0);
    tnear_out[i] = tnear;
    from_mirror[i] = m ? unit : -1;
    from_camera[i] = m ? -1 : unit;
  }
}

// Thin-lens camera rays of n image points of an undistorted camera (or of undistorted normalised points, given
// with unit focal lengths and a zero principal point), mapped to a target frame. With thin = 1, the ray
// from the aperture point o = lens_radius (disc_x, disc_y, 0) towards the pinhole ray's point on the plane
// z = focus_distance, f (x, y, 1) with (x, y) = ((u - cx) / fx, (v - cy) / fy); with thin = 0, from the centre
// along (x, y, 1). Directions normalised (one square root and one division per ray); origin and direction mapped by
// target_from_cam (R column-major, t: mirror_from_cam for a unit, world_from_cam for a pinhole view). ifx, ify:
// 1 / fx, 1 / fy.
HOVS_VECTOR_CLONES
void ThinLensRays(int n, double ifx, double ify, double cx, double cy, double lens_radius, double focus_distance,
                  int thin, const double* __restrict R, const double* __restrict t, const double* __restrict u,
                  const double* __restrict v, const double* __restrict disc_x, const double* __restrict disc_y,
                  double* __restrict omx, double* __restrict omy, double* __restrict omz, double* __restrict vmx,
                  double* __restrict vmy, double* __restrict vmz) {
  const double f = thin ? focus_distance : 1.0, r = thin ? lens_radius : 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = (u[i] - cx) * ifx, y = (v[i] - cy) * ify;
    const double ox = r * disc_x[i], oy = r * disc_y[i];
    const double ex = x * f - ox, ey = y * f - oy, ez = f;
    const double inv = 1.0 / std::sqrt(ex * ex + ey * ey + ez * ez);
    const double dx = ex * inv, dy = ey * inv, dz = ez * inv;
    omx[i] = R[0] * ox + R[3] * oy + t[0];
    omy[i] = R[1] * ox + R[4] * oy + t[1];
    omz[i] = R[2] * ox + R[5] * oy + t[2];
    vmx[i] = R[0] * dx + R[3] * dy + R[6] * dz;
    vmy[i] = R[1] * dx + R[4] * dy + R[7] * dz;
    vmz[i] = R[2] * dx + R[5] * dy + R[8] * dz;
  }
}

// The world rays of thin-lens samples (ThinLensRays, then the mirror): where on_mirror[i], from the mirror point M
// along the reflected direction, else from the aperture point along the camera ray (both in the mirror frame),
// mapped by world_from_mirror (R column-major, t) at the sample's time tau[i]: kMoving, the rotation by rate *
// tau about the axis (Rodrigues' formula; its sine and cosine from core/sincos.h) after R, and t + velocity *
// tau; else at time 0.
template <bool kMoving>
__attribute__((always_inline)) inline void ThinLensWorldRaysOf(
    int n, const unsigned char* __restrict on_mirror, int unit, const double* __restrict R, const double* __restrict t,
    const UnitMotion& motion, const LensRayRing& ring, const double* __restrict tau, const double* __restrict Mx,
    const double* __restrict My, const double* __restrict Mz, const double* __restrict mdx,
    const double* __restrict mdy, const double* __restrict mdz, const double* __restrict omx,
    const double* __restrict omy, const double* __restrict omz, const double* __restrict vmx,
    const double* __restrict vmy, const double* __restrict vmz, double* __restrict ox, double* __restrict oy,
    double* __restrict oz, double* __restrict dx, double* __restrict dy, double* __restrict dz,
    int* __restrict from_mirror, int* __restrict from_camera, double* __restrict mount_t) {
  const double zr = ring.zr, r02 = ring.r02, r12 = ring.r12;
  const int own_unit = ring.own ? unit : -1, ring_test = ring.own & ring.ring;
  const double a0 = motion.axis[0], a1 = motion.axis[1], a2 = motion.axis[2], turns = motion.rate / (2 * M_PI);
  const double w0 = motion.velocity[0], w1 = motion.velocity[1], w2 = motion.velocity[2];
  for (int i = 0; i < n; ++i) {
    const bool m = on_mirror[i] != 0;
    const double X0 = m ? Mx[i] : omx[i], X1 = m ? My[i] : omy[i], X2 = m ? Mz[i] : omz[i];
    const double D0 = m ? mdx[i] : vmx[i], D1 = m ? mdy[i] : vmy[i], D2 = m ? mdz[i] : vmz[i];
    double p0 = R[0] * X0 + R[3] * X1 + R[6] * X2, p1 = R[1] * X0 + R[4] * X1 + R[7] * X2,
           p2 = R[2] * X0 + R[5] * X1 + R[8] * X2;
    double q0 = R[0] * D0 + R[3] * D1 + R[6] * D2, q1 = R[1] * D0 + R[4] * D1 + R[7] * D2,
           q2 = R[2] * D0 + R[5] * D1 + R[8] * D2;
    double e0 = t[0], e1 = t[1], e2 = t[2];
    if (kMoving) {
      double sn, cs;
      SinCosOfTurns(turns * tau[i], &sn, &cs);
      const double k = 1 - cs;
      const double ap = a0 * p0 + a1 * p1 + a2 * p2, aq = a0 * q0 + a1 * q1 + a2 * q2;
      const double r0 = cs * p0 + sn * (a1 * p2 - a2 * p1) + k * ap * a0;
      const double r1 = cs * p1 + sn * (a2 * p0 - a0 * p2) + k * ap * a1;
      const double r2 = cs * p2 + sn * (a0 * p1 - a1 * p0) + k * ap * a2;
      const double s0 = cs * q0 + sn * (a1 * q2 - a2 * q1) + k * aq * a0;
      const double s1 = cs * q1 + sn * (a2 * q0 - a0 * q2) + k * aq * a1;
      const double s2 = cs * q2 + sn * (a0 * q1 - a1 * q0) + k * aq * a2;
      p0 = r0, p1 = r1, p2 = r2, q0 = s0, q1 = s1, q2 = s2;
      e0 += w0 * tau[i], e1 += w1 * tau[i], e2 += w2 * tau[i];
    }
    ox[i] = p0 + e0, oy[i] = p1 + e1, oz[i] = p2 + e2;
    dx[i] = q0, dy[i] = q1, dz[i] = q2;
    from_mirror[i] = m ? unit : -1;
    // A straight ray's distance to the mount ring (the mirror-frame ray: vm is unit, so t is the distance along
    // the world ray, at any time); 0 where it misses the ring, -1 where not computed.
    const double w = vmz[i] != 0 ? vmz[i] : 1.0;
    const double tr = (zr - omz[i]) / w, px = omx[i] + tr * vmx[i], py = omy[i] + tr * vmy[i];
    const double r2 = px * px + py * py;
    const bool hits_ring = vmz[i] != 0 && tr > 1e-5 && r2 >= r02 && r2 <= r12;
    from_camera[i] = m ? -1 : own_unit;
    mount_t[i] = m ? -1.0 : (ring_test ? (hits_ring ? tr : 0.0) : -1.0);
  }
}

HOVS_VECTOR_CLONES
void ThinLensWorldRays(int n, const unsigned char* __restrict on_mirror, int unit, const double* __restrict R,
                       const double* __restrict t, const UnitMotion& motion, const LensRayRing& ring,
                       const double* __restrict tau, const double* __restrict Mx, const double* __restrict My,
                       const double* __restrict Mz, const double* __restrict mdx, const double* __restrict mdy,
                       const double* __restrict mdz, const double* __restrict omx, const double* __restrict omy,
                       const double* __restrict omz, const double* __restrict vmx, const double* __restrict vmy,
                       const double* __restrict vmz, double* __restrict ox, double* __restrict oy,
                       double* __restrict oz, double* __restrict dx, double* __restrict dy, double* __restrict dz,
                       int* __restrict from_mirror, int* __restrict from_camera, double* __restrict mount_t) {
  if (tau) {
    ThinLensWorldRaysOf<true>(n, on_mirror, unit, R, t, motion, ring, tau, Mx, My, Mz, mdx, mdy, mdz, omx, omy, omz,
                              vmx, vmy, vmz, ox, oy, oz, dx, dy, dz, from_mirror, from_camera, mount_t);
  } else {
    ThinLensWorldRaysOf<false>(n, on_mirror, unit, R, t, motion, ring, tau, Mx, My, Mz, mdx, mdy, mdz, omx, omy, omz,
                               vmx, vmy, vmz, ox, oy, oz, dx, dy, dz, from_mirror, from_camera, mount_t);
  }
}

}  // namespace

template <class T>
void RayMaker::SetFrame(UnitRayFrame<T>* f) const {
  f->zr = static_cast<T>(unit_->rig.mirror.RimZ());
  f->r0 = static_cast<T>(unit_->rig.mirror.RimRadius());
  f->r1 = static_cast<T>(unit_->mount_outer_radius);
  for (int k = 0; k < 3; ++k) {
    f->c_m[k] = static_cast<T>(t_mirror_from_cam_(k));
    f->t[k] = static_cast<T>(t_world_from_mirror_(k));
    f->c_w[k] = static_cast<T>(world_from_cam_.translation(k));
  }
  for (int k = 0; k < 9; ++k) f->R[k] = static_cast<T>(R_world_from_mirror_.data()[k]);
}

RayMaker::RayMaker(const RayScene& scene, const ViewCamera& cam, const RenderOptions& o)
    : scene_(scene), cam_(cam), lens_radius_(o.lens_radius), focus_distance_(o.focus_distance) {
  if (cam.unit >= 0) {
    HOVS_REQUIRE(cam.unit < static_cast<int>(scene.description().units.size()), "render", "the scene has no unit ",
                 cam.unit);
    unit_ = &scene.description().units[cam.unit];
    reflector_.emplace(unit_->rig.mirror);
    mirror_from_cam_ = unit_->rig.cam_from_mirror.Inverse();
    world_from_cam_ = unit_->world_from_mirror * mirror_from_cam_;
    // Rotation matrices for the per-sample transforms (a quaternion rotation costs twice as much).
    R_mirror_from_cam_ = mirror_from_cam_.rotation.toRotationMatrix(),
    t_mirror_from_cam_ = mirror_from_cam_.translation;
    R_world_from_mirror_ = unit_->world_from_mirror.rotation.toRotationMatrix();
    t_world_from_mirror_ = unit_->world_from_mirror.translation;
    viewpoint_ = unit_->world_from_mirror.translation;
    width_ = unit_->rig.camera.width, height_ = unit_->rig.camera.height;
    // The single-precision colour path: a unit's camera without distortion, at time 0, through a pinhole.
    single_ = unit_->rig.camera.distortion.IsZero() && !(o.lens_radius > 0) && !(o.exposure_time > 0);
    R_mirror_from_cam_f_ = R_mirror_from_cam_.cast<float>();
    SetFrame(&frame_d_), SetFrame(&frame_f_);
    motion_.rate = unit_->angular_velocity.norm();
    if (motion_.rate > 0)
      for (int k = 0; k < 3; ++k) motion_.axis[k] = unit_->angular_velocity(k) / motion_.rate;
    for (int k = 0; k < 3; ++k) motion_.velocity[k] = unit_->velocity(k);
    // Thin-lens samples past the rim are the unit's own straight camera rays when the whole aperture lies inside
    // the mirror's lower nappe, as the camera centre does: from there a ray that misses the mirror within the rim
    // never meets it (MirrorReflector::MissesRim's argument), and it leaves the lens face forwards.
    lens_ring_.own = ApertureInLowerNappe() ? 1 : 0;
    lens_ring_.ring = unit_->mount_outer_radius > 0 ? 1 : 0;
    lens_ring_.zr = unit_->rig.mirror.RimZ();
    lens_ring_.r02 = unit_->rig.mirror.RimRadius() * unit_->rig.mirror.RimRadius();
    lens_ring_.r12 = unit_->mount_outer_radius * unit_->mount_outer_radius;
    // Under motion blur the path from the camera to the mount ring must stay clear over the whole exposure.
    mount_paths_clear_ = !(o.exposure_time > 0) || scene.MountPathClearDuring(cam.unit, o.exposure_time);
  } else {
    cam.pinhole.Check("render camera");
    world_from_cam_ = cam.world_from_cam;
    viewpoint_ = cam.world_from_cam.translation;
    width_ = cam.pinhole.width, height_ = cam.pinhole.height;
  }
  R_world_from_cam_ = world_from_cam_.rotation.toRotationMatrix();
  HOVS_REQUIRE(width_ > 0 && height_ > 0, "render", "the camera has no image size");
}

void RayMaker::MakeBatchF(int n, const double* u, const double* v, RayBatchF* b) const {
  b->n = n;
  b->timed = false, b->mirror_frame = false, b->mount_paths_clear = true;
  const PinholeCamera<double>& cam = unit_->rig.camera;
  alignas(64) float vx[RayBatch::kMax], vy[RayBatch::kMax], vz[RayBatch::kMax];
  alignas(64) float Mx[RayBatch::kMax], My[RayBatch::kMax], Mz[RayBatch::kMax];
  unsigned char on_mirror[RayBatch::kMax];
  PixelRaysF(n, cam.cx, cam.cy, static_cast<float>(1.0 / cam.fx), static_cast<float>(1.0 / cam.fy),
             R_mirror_from_cam_f_.data(), u, v, vx, vy, vz);
  std::fill(b->valid, b->valid + n, 1);
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
  const int on =
      reflector_->ReflectBatch(t_mirror_from_cam_, n, vx, vy, vz, Mx, My, Mz, b->dx, b->dy, b->dz, on_mirror);
  // (A batch whose rays all meet the mirror, most of them, has no straight ray: no ring test.)
  UnitRays<float>(n, on, on_mirror, cam_.unit, 1e-5f, unit_->mount_outer_radius > 0 && on < n, &frame_f_, vx, vy, vz,
                  Mx, My, Mz, b->dx, b->dy, b->dz, b->ox, b->oy, b->oz, b->tnear, b->from_mirror, b->from_camera,
                  b->mount_t);
#pragma GCC diagnostic pop
}

void RayMaker::MakeBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                         const double* tau, RayBatch* b, double* Mx, double* My, double* Mz, const double* nx,
                         const double* ny) const {
  b->n = n;
  b->timed = false, b->mirror_frame = false, b->mount_paths_clear = true;
  if ((lens_x || tau) && unit_) {
    MakeLensBatch(n, u, v, lens_x, lens_y, tau, b, Mx, My, Mz);
    return;
  }
  if (lens_x || tau) {  // a pinhole view through a thin lens (pinhole views do not move)
    MakePinholeLensBatch(n, u, v, lens_x, lens_y, b);
    std::fill(Mx, Mx + n, 0.0), std::fill(My, My + n, 0.0), std::fill(Mz, Mz + n, 0.0);  // no mirror
    return;
  }
  const PinholeCamera<double>& cam = unit_ ? unit_->rig.camera : cam_.pinhole;
  // The unit camera rays, in the mirror frame for a unit (reflected together), in the world for a pinhole.
  double vx[RayBatch::kMax], vy[RayBatch::kMax], vz[RayBatch::kMax];
  const double* R = unit_ ? R_mirror_from_cam_.data() : R_world_from_cam_.data();
  if (nx && ny && cam.distortion.IsZero()) {
    RotateRays(n, R, nx, ny, vx, vy, vz);
    std::fill(b->valid, b->valid + n, 1);
  } else if (cam.distortion.IsZero()) {
    PixelRays(n, cam.fx, cam.fy, cam.cx, cam.cy, R, u, v, vx, vy, vz);
    std::fill(b->valid, b->valid + n, 1);
  } else {
    double mx[RayBatch::kMax], my[RayBatch::kMax];
    cam.NormalisedFromImgBatch(n, u, v, mx, my, b->valid);
    RotateRays(n, R, mx, my, vx, vy, vz);
  }
  unsigned char on_mirror[RayBatch::kMax];
  // (GCC 12 reports the arrays as maybe uninitialised when n could be 0; the callees read only [0, n).)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
  if (unit_) {
    const int on =
        reflector_->ReflectBatch(t_mirror_from_cam_, n, vx, vy, vz, Mx, My, Mz, b->dx, b->dy, b->dz, on_mirror);
    // Camera rays past the rim: where they meet the unit's mount ring, in the mirror frame where the rim test
    // was made (the world ray is the same ray rotated and moved, so the distance along it is the same).
    // RayScene traces them only up to it. tnear 1e-5: off the mirror, or off the lens face.
    // (A batch whose rays all meet the mirror, most of them, has no straight ray: no ring test.) Both kinds of
    // ray from the mirror frame to the world in one rotation.
    UnitRays<double>(n, on, on_mirror, cam_.unit, 1e-5f, unit_->mount_outer_radius > 0 && on < n, &frame_d_, vx, vy, vz,
                     Mx, My, Mz, b->dx, b->dy, b->dz, b->ox, b->oy, b->oz, b->tnear, b->from_mirror, b->from_camera,
                     b->mount_t);
  } else {
    std::fill(on_mirror, on_mirror + n, 0);
    double via[RayBatch::kMax];  // on_mirror as 0 / 1 (the pinhole camera has no mirror: all 0)
    RayOrigins(n, on_mirror, -1, 0.0f, via, b->tnear, b->from_mirror, b->from_camera);
    std::fill(b->mount_t, b->mount_t + n, -1.0);
    std::copy(vx, vx + n, b->dx), std::copy(vy, vy + n, b->dy), std::copy(vz, vz + n, b->dz);
    std::fill(b->ox, b->ox + n, world_from_cam_.translation.x());
    std::fill(b->oy, b->oy + n, world_from_cam_.translation.y());
    std::fill(b->oz, b->oz + n, world_from_cam_.translation.z());
  }
#pragma GCC diagnostic pop
}

void RayMaker::MakeLensBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                             const double* tau, RayBatch* b, double* Mx, double* My, double* Mz) const {
  alignas(64) double omx[RayBatch::kMax], omy[RayBatch::kMax], omz[RayBatch::kMax], vmx[RayBatch::kMax],
      vmy[RayBatch::kMax], vmz[RayBatch::kMax];
  alignas(64) double mdx[RayBatch::kMax], mdy[RayBatch::kMax], mdz[RayBatch::kMax];
  unsigned char on_mirror[RayBatch::kMax];
  CameraLensRays(unit_->rig.camera, R_mirror_from_cam_.data(), t_mirror_from_cam_.data(), n, u, v, lens_x, lens_y,
                 b->valid, omx, omy, omz, vmx, vmy, vmz);
  reflector_->ReflectRays(n, omx, omy, omz, vmx, vmy, vmz, Mx, My, Mz, mdx, mdy, mdz, on_mirror);
  ThinLensWorldRays(n, on_mirror, cam_.unit, R_world_from_mirror_.data(), t_world_from_mirror_.data(), motion_,
                    lens_ring_, tau, Mx, My, Mz, mdx, mdy, mdz, omx, omy, omz, vmx, vmy, vmz, b->ox, b->oy, b->oz,
                    b->dx, b->dy, b->dz, b->from_mirror, b->from_camera, b->mount_t);
  // tnear 1e-5: off the mirror's sheet (float rounding of the origin), or off the camera's lens face.
  std::fill(b->tnear, b->tnear + n, 1e-5f);
  // Each ray's time, at which RayScene meets the moving units' parts.
  b->timed = tau != nullptr;
  b->mount_paths_clear = tau == nullptr || mount_paths_clear_;
  if (tau)
    for (int i = 0; i < n; ++i) b->time[i] = static_cast<float>(tau[i]);
  // The mirror rays in the mirror frame, where RayScene meets the moving unit's own parts.
  b->mirror_frame = scene_.OwnPartsInMirrorFrame(cam_.unit);
  if (b->mirror_frame) {
    std::copy(Mx, Mx + n, b->mox), std::copy(My, My + n, b->moy), std::copy(Mz, Mz + n, b->moz);
    std::copy(mdx, mdx + n, b->mdx), std::copy(mdy, mdy + n, b->mdy), std::copy(mdz, mdz + n, b->mdz);
  }
}

void RayMaker::MakePinholeLensBatch(int n, const double* u, const double* v, const double* lens_x, const double* lens_y,
                                    RayBatch* b) const {
  CameraLensRays(cam_.pinhole, R_world_from_cam_.data(), world_from_cam_.translation.data(), n, u, v, lens_x, lens_y,
                 b->valid, b->ox, b->oy, b->oz, b->dx, b->dy, b->dz);
  std::fill(b->tnear, b->tnear + n, 0.0f);
  std::fill(b->from_mirror, b->from_mirror + n, -1);
  std::fill(b->from_camera, b->from_camera + n, -1);
  std::fill(b->mount_t, b->mount_t + n, -1.0);
}

void RayMaker::CameraLensRays(const PinholeCamera<double>& cam, const double* R, const double* t, int n,
                              const double* u, const double* v, const double* lens_x, const double* lens_y,
                              unsigned char* valid, double* ox, double* oy, double* oz, double* dx, double* dy,
                              double* dz) const {
  const bool thin = lens_x && lens_radius_ > 0, distorted = !cam.distortion.IsZero();
  alignas(64) double zeros[RayBatch::kMax], xn[RayBatch::kMax], yn[RayBatch::kMax];
  if (!thin) std::fill(zeros, zeros + n, 0.0);
  if (distorted) {
    cam.NormalisedFromImgBatch(n, u, v, xn, yn, valid);
  } else {
    std::fill(valid, valid + n, 1);
  }
  ThinLensRays(n, distorted ? 1.0 : 1.0 / cam.fx, distorted ? 1.0 : 1.0 / cam.fy, distorted ? 0.0 : cam.cx,
               distorted ? 0.0 : cam.cy, lens_radius_, focus_distance_, thin ? 1 : 0, R, t, distorted ? xn : u,
               distorted ? yn : v, thin ? lens_x : zeros, thin ? lens_y : zeros, ox, oy, oz, dx, dy, dz);
}

bool RayMaker::ApertureInLowerNappe() const {
  const HyperboloidMirror<double>& mirror = unit_->rig.mirror;
  const double c = mirror.c(), ia2 = 1 / (mirror.a * mirror.a), ib2 = 1 / (mirror.b * mirror.b);
  const int k = 64;
  const double r = lens_radius_ / std::cos(M_PI / k);
  for (int i = 0; i < k; ++i) {
    const Vec3d p = mirror_from_cam_ * Vec3d(r * std::cos(2 * M_PI * i / k), r * std::sin(2 * M_PI * i / k), 0);
    const double oz = p.z() + c;
    if (!(oz < 0 && oz * oz * ia2 - (p.x() * p.x() + p.y() * p.y()) * ib2 >= 1 + 1e-9 && p.z() < mirror.RimZ()))
      return false;
  }
  return true;
}

}  // namespace hovs::raytrace
