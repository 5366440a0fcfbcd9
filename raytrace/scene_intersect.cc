#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.h"
#include "core/vector_clones.h"
#include "raytrace/scene_internal.h"

namespace hovs::raytrace {
using namespace internal;

namespace {

// Fills a 16-wide packet (lanes past count are masked off) and intersects it with the scene.
template <int W, class RayHitW, class IntersectW>
void IntersectPacketW(RTCScene scene, int count, const Vec3d* o, const Vec3d* d, const double* tnear,
                      const int* from_mirror, RayHitW* rh, IntersectW intersect) {
  alignas(64) int valid[W];
  for (int i = 0; i < W; ++i) {
    valid[i] = i < count ? -1 : 0;
    const int k = i < count ? i : 0;
    rh->ray.org_x[i] = static_cast<float>(o[k].x()), rh->ray.org_y[i] = static_cast<float>(o[k].y());
    rh->ray.org_z[i] = static_cast<float>(o[k].z());
    rh->ray.dir_x[i] = static_cast<float>(d[k].x()), rh->ray.dir_y[i] = static_cast<float>(d[k].y());
    rh->ray.dir_z[i] = static_cast<float>(d[k].z());
    SetLane(rh, i, static_cast<float>(tnear ? tnear[k] : 0.0), from_mirror ? from_mirror[k] : -1, -1);
  }
  TracePacket(scene, valid, rh, intersect);
}

void IntersectPacket(RTCScene scene, int count, const Vec3d* o, const Vec3d* d, const double* tnear,
                     const int* from_mirror, RTCRayHit16* rh) {
  IntersectPacketW<16>(scene, count, o, d, tnear, from_mirror, rh, rtcIntersect16);
}
}  // namespace

void RayScene::Trace16(int count, const Vec3d* o, const Vec3d* d, const double* tnear, Hit* hits,
                       const int* from_mirror, bool colour) const {
  alignas(64) RTCRayHit16 rh;
  IntersectPacket(scene_, count, o, d, tnear, from_mirror, &rh);
  if (!instances_.empty()) MapInstanceHits(count, rh.hit.instID[0], rh.hit.geomID, rh.hit.primID);
  for (int i = 0; i < count; ++i) {
    Hit& h = hits[i];
    h = Hit();
    if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) {
      if (colour) h.colour = desc_.sky.Eval(d[i]);
      continue;
    }
    Shade(o[i], d[i], rh.hit.geomID[i], rh.hit.primID[i], &h, colour);
  }
}

namespace {

// Packet fields of w full lanes from batch arrays (already offset to the packet's first ray): the conversions
// to float (copies for T = float), the masks (RayMask less mask_off) and ids; tfar is infinite except where
// tfar_in > 0.
// W: the packet width, a constant (for T = float the conversions are copies, which GCC otherwise turns into a
// library memcpy call each).
template <class T, int W>
HOVS_VECTOR_CLONES void FillPacket(const T* __restrict ox, const T* __restrict oy, const T* __restrict oz,
                                   const T* __restrict dx, const T* __restrict dy, const T* __restrict dz,
                                   const float* __restrict tnear, const int* __restrict from_mirror,
                                   const int* __restrict from_camera, const float* __restrict tfar_in,
                                   const unsigned* __restrict mask_off, float* __restrict org_x,
                                   float* __restrict org_y, float* __restrict org_z, float* __restrict dir_x,
                                   float* __restrict dir_y, float* __restrict dir_z, float* __restrict tnear_out,
                                   float* __restrict tfar, unsigned* __restrict mask, unsigned* __restrict id,
                                   unsigned* __restrict flags, float* __restrict time, unsigned* __restrict geom,
                                   unsigned* __restrict inst) {
  for (int i = 0; i < W; ++i) {
    org_x[i] = static_cast<float>(ox[i]), org_y[i] = static_cast<float>(oy[i]), org_z[i] = static_cast<float>(oz[i]);
    dir_x[i] = static_cast<float>(dx[i]), dir_y[i] = static_cast<float>(dy[i]), dir_z[i] = static_cast<float>(dz[i]);
    tnear_out[i] = tnear[i];
    tfar[i] = tfar_in[i] > 0 ? tfar_in[i] : std::numeric_limits<float>::infinity();
    mask[i] = RayMask(from_mirror[i], from_camera[i]) & ~mask_off[i];
    id[i] = from_mirror[i] >= 0 ? static_cast<unsigned>(from_mirror[i]) + 1 : 0u;
    flags[i] = 0, time[i] = 0;
    geom[i] = RTC_INVALID_GEOMETRY_ID, inst[i] = RTC_INVALID_GEOMETRY_ID;
  }
}

// The common case of PrepareLanes without branches: every straight camera ray of the batch leaves unit U's
// camera with its ring distance computed.
template <class T>
HOVS_VECTOR_CLONES void RingLanes(int n, const unsigned char* __restrict bvalid, const int* __restrict from_camera,
                                  const T* __restrict mount_t, int U, unsigned bit, int clear, int* __restrict valid,
                                  float* __restrict tfar, unsigned* __restrict mask_off, unsigned ring_geom,
                                  unsigned* __restrict mount_geom) {
  const int match = U >= 0 ? U : -1000;  // no unit: no lane is a ring lane
  // As 0 / 1 arithmetic, not selects: GCC 12 vectorises the selects here only with a branch per vector.
  for (int i = 0; i < n; ++i) {
    const T t = mount_t[i];
    const int live = bvalid[i] != 0;
    const int ring = live & (from_camera[i] == match) & (t > 0);
    tfar[i] = static_cast<float>(t) * static_cast<float>(ring);  // 0 (or -0) where not a ring lane
    mask_off[i] = bit & static_cast<unsigned>(-ring);
    mount_geom[i] = ring_geom | static_cast<unsigned>(ring - 1);  // ring ? ring_geom : RTC_INVALID_GEOMETRY_ID
    valid[i] = -(live & (1 - (ring & clear)));                    // nothing in between: no Embree for this lane
  }
}

// The unit of a batch's straight camera rays (the largest from_camera; -1: none) and whether every straight ray
// is that unit's with its ring distance computed (uniform): one pass without branches.
template <class T>
HOVS_VECTOR_CLONES int CameraLanes(int n, const int* __restrict from_camera, const T* __restrict mount_t,
                                   bool* uniform) {
  int U = -1;
  for (int i = 0; i < n; ++i) U = std::max(U, from_camera[i]);
  int odd = 0;
  for (int i = 0; i < n; ++i) odd |= (from_camera[i] >= 0) & ((from_camera[i] != U) | !(mount_t[i] >= 0));
  *uniform = odd == 0;
  return U;
}

template <class T>
void PrepareLanes(const RayBatchOf<T>& b, const std::vector<RayScene::OwnMount>& mounts, BatchLanes* L) {
  const int n = b.n;
  bool uniform = false;
  const int U = CameraLanes(n, b.from_camera, b.mount_t, &uniform);
  uniform = uniform && U >= 0 && static_cast<size_t>(U) < mounts.size() && mounts[U].geometry != nullptr;
  if (uniform || U < 0) {  // U < 0: no straight camera ray at all (no lane is a ring lane)
    RingLanes(n, b.valid, b.from_camera, b.mount_t, U, U >= 0 ? MountMaskBit(U) : 0u,
              U >= 0 && mounts[U].path_clear && b.mount_paths_clear ? 1 : 0, L->valid, L->tfar, L->mask_off,
              U >= 0 ? mounts[U].geom_id : RTC_INVALID_GEOMETRY_ID, L->mount_geom);
    return;
  }
  for (int j = 0; j < n; ++j) {
    L->valid[j] = b.valid[j] ? -1 : 0;
    L->tfar[j] = 0, L->mask_off[j] = 0, L->mount_geom[j] = RTC_INVALID_GEOMETRY_ID;
    const int u = b.from_camera[j];
    if (!b.valid[j] || u < 0 || static_cast<size_t>(u) >= mounts.size() || !mounts[u].geometry) continue;
    double t = b.mount_t[j];
    if (t < 0 && !mounts[u].geometry->Intersect(Vec3d(b.ox[j], b.oy[j], b.oz[j]), Vec3d(b.dx[j], b.dy[j], b.dz[j]),
                                                b.tnear[j], HUGE_VAL, &t, nullptr))
      continue;
    if (t <= 0) continue;
    L->tfar[j] = static_cast<float>(t);
    L->mask_off[j] = MountMaskBit(u);
    L->mount_geom[j] = mounts[u].geom_id;
    // Nothing can be in between (and the ray starts at the camera centre, as the path test assumes).
    if (mounts[u].path_clear && b.mount_paths_clear && b.mount_t[j] > 0) L->valid[j] = 0;
  }
}

// Batch rays [i0, i0 + W) (fewer at the end) as one Embree packet of width W (RTCRayHit8 or RTCRayHit16).
// Rays with times (b.timed) take time = b.time * inv_horizon in Embree's [0, 1] (a moving unit's instance); the
// hits' instance ids go to inst_ids when it is given (the scene has moving units), else they are not needed.
template <int W, class RayHitW, class T, class IntersectW>
void TracePacketOfBatch(RTCScene scene, const RayBatchOf<T>& b, const BatchLanes& L, int i0, unsigned* geom_ids,
                        unsigned* prim_ids, unsigned* inst_ids, float inv_horizon, IntersectW intersect) {
  const int count = std::min(W, b.n - i0);
  int any = 0;
  if (count == W) {  // (as vectors of four lanes: GCC leaves the plain loop scalar)
    typedef int Lanes4 __attribute__((vector_size(16)));
    Lanes4 acc = {0, 0, 0, 0};
    for (int i = 0; i < W; i += 4) {
      Lanes4 x;
      std::memcpy(&x, L.valid + i0 + i, sizeof x);
      acc |= x;
    }
    any = acc[0] | acc[1] | acc[2] | acc[3];
  } else {
    for (int i = 0; i < count; ++i) any |= L.valid[i0 + i];
  }
  if (!any) {          // every lane ends on its ring or is invalid: ResolveMisses gives them the ring
    if (count == W) {  // (a constant size: vector stores, not library calls)
      for (int i = 0; i < W; ++i) geom_ids[i] = RTC_INVALID_GEOMETRY_ID;  // (two loops: the arrays may alias)
      for (int i = 0; i < W; ++i) prim_ids[i] = 0u;
    } else {
      std::fill(geom_ids, geom_ids + count, RTC_INVALID_GEOMETRY_ID);
      std::fill(prim_ids, prim_ids + count, 0u);
    }
    if (inst_ids) std::fill(inst_ids, inst_ids + count, RTC_INVALID_GEOMETRY_ID);
    return;
  }
  alignas(64) RayHitW rh;
  alignas(64) int partial_valid[W];
  const int* valid = L.valid + i0;  // 64-byte aligned for W = 16 (i0 a multiple of 16), 32-byte for W = 8
  if (count == W) {
    FillPacket<T, W>(b.ox + i0, b.oy + i0, b.oz + i0, b.dx + i0, b.dy + i0, b.dz + i0, b.tnear + i0, b.from_mirror + i0,
                     b.from_camera + i0, L.tfar + i0, L.mask_off + i0, rh.ray.org_x, rh.ray.org_y, rh.ray.org_z,
                     rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z, rh.ray.tnear, rh.ray.tfar, rh.ray.mask, rh.ray.id,
                     rh.ray.flags, rh.ray.time, rh.hit.geomID, rh.hit.instID[0]);
  } else {
    // Lanes past count repeat the batch's ray i0, masked off.
    for (int i = 0; i < W; ++i) {
      const int j = i0 + (i < count ? i : 0);
      partial_valid[i] = i < count ? L.valid[j] : 0;
      rh.ray.org_x[i] = static_cast<float>(b.ox[j]), rh.ray.org_y[i] = static_cast<float>(b.oy[j]);
      rh.ray.org_z[i] = static_cast<float>(b.oz[j]);
      rh.ray.dir_x[i] = static_cast<float>(b.dx[j]), rh.ray.dir_y[i] = static_cast<float>(b.dy[j]);
      rh.ray.dir_z[i] = static_cast<float>(b.dz[j]);
      SetLane(&rh, i, b.tnear[j], b.from_mirror[j], b.from_camera[j]);
      if (L.tfar[j] > 0) rh.ray.tfar[i] = L.tfar[j];
      rh.ray.mask[i] &= ~L.mask_off[j];
    }
    valid = partial_valid;
  }
  if (b.timed) {
    for (int i = 0; i < W; ++i) {
      const int j = i0 + (i < count ? i : 0);
      rh.ray.time[i] = std::min(std::max(b.time[j] * inv_horizon, 0.0f), 1.0f);
    }
  }
  TracePacket(scene, valid, &rh, intersect);
  if (inst_ids && count == W) {  // (a constant size: vector moves, not a library call)
    std::memcpy(inst_ids, rh.hit.instID[0], sizeof(unsigned) * W);
  } else if (inst_ids) {
    std::memcpy(inst_ids, rh.hit.instID[0], sizeof(unsigned) * static_cast<size_t>(count));
  }
  if (count == W) {  // (a constant size: vector moves, not a library call)
    std::memcpy(geom_ids, rh.hit.geomID, sizeof(unsigned) * W);
    std::memcpy(prim_ids, rh.hit.primID, sizeof(unsigned) * W);
  } else {
    std::memcpy(geom_ids, rh.hit.geomID, sizeof(unsigned) * static_cast<size_t>(count));
    std::memcpy(prim_ids, rh.hit.primID, sizeof(unsigned) * static_cast<size_t>(count));
  }
}

// After the packets of a batch: a lane Embree found nothing for ends on its ring, if it has one (prim 0; a
// miss's prim is never read otherwise).
HOVS_VECTOR_CLONES void ResolveMisses(int n, const unsigned* __restrict mount_geom, unsigned* __restrict geom_ids,
                                      unsigned* __restrict prim_ids) {
  for (int i = 0; i < n; ++i) {
    const bool miss = geom_ids[i] == RTC_INVALID_GEOMETRY_ID;
    geom_ids[i] = miss ? mount_geom[i] : geom_ids[i];
    prim_ids[i] = miss ? 0u : prim_ids[i];
  }
}

}  // namespace

namespace {

// Rays from the world to a frame: o' = R o + t, d' = R d (R column-major). Vectorised.
template <class T>
HOVS_VECTOR_CLONES void RaysToFrame(int n, const double* __restrict Rd, const double* __restrict td,
                                    const T* __restrict ox, const T* __restrict oy, const T* __restrict oz,
                                    const T* __restrict dx, const T* __restrict dy, const T* __restrict dz,
                                    T* __restrict fox, T* __restrict foy, T* __restrict foz, T* __restrict fdx,
                                    T* __restrict fdy, T* __restrict fdz) {
  T R[9], t[3];
  for (int k = 0; k < 9; ++k) R[k] = static_cast<T>(Rd[k]);
  for (int k = 0; k < 3; ++k) t[k] = static_cast<T>(td[k]);
  for (int i = 0; i < n; ++i) {
    const T o0 = ox[i], o1 = oy[i], o2 = oz[i], d0 = dx[i], d1 = dy[i], d2 = dz[i];
    fox[i] = R[0] * o0 + R[3] * o1 + R[6] * o2 + t[0];
    foy[i] = R[1] * o0 + R[4] * o1 + R[7] * o2 + t[1];
    foz[i] = R[2] * o0 + R[5] * o1 + R[8] * o2 + t[2];
    fdx[i] = R[0] * d0 + R[3] * d1 + R[6] * d2;
    fdy[i] = R[1] * d0 + R[4] * d1 + R[7] * d2;
    fdz[i] = R[2] * d0 + R[5] * d1 + R[8] * d2;
  }
}

// The nearest of a moving unit's own parts along its rays in its mirror frame (OwnPartShapes): part[i] = 0 none,
// 1 the lens face, 2 the mount ring, 3 + f the body's rectangle f (MakeBox's order: top, bottom, +x, -x, +y, -y),
// at distance t[i] beyond tnear[i], for lanes with active[i]. The disc and annulus as UserGeometry's tests (a
// plane, then the radius), the box by slabs in the camera frame (where the ray enters it). A ray parallel to a
// plane gives an infinite or undefined distance, which no comparison passes. Vectorised. sh: R_cam_from_mirror
// (9, column-major), t_cam_from_mirror (3), lens_r2, rim_z, rim_r2, mount_r2, half, length.
template <class T>
HOVS_VECTOR_CLONES void OwnPartLanes(int n, const unsigned char* __restrict active, const T* __restrict ox_in,
                                     const T* __restrict oy_in, const T* __restrict oz_in, const T* __restrict dx_in,
                                     const T* __restrict dy_in, const T* __restrict dz_in,
                                     const float* __restrict tnear, const double* __restrict sh, int* __restrict part,
                                     float* __restrict tout) {
  // In single precision whatever the rays' (Embree, which takes the distance, traces in it; which part a ray
  // meets differs from a double-precision test only within about 1e-7 m of a part's edge).
  alignas(64) float ox[RayBatch::kMax], oy[RayBatch::kMax], oz[RayBatch::kMax], dx[RayBatch::kMax], dy[RayBatch::kMax],
      dz[RayBatch::kMax];
  for (int i = 0; i < n; ++i) {
    ox[i] = static_cast<float>(ox_in[i]), oy[i] = static_cast<float>(oy_in[i]), oz[i] = static_cast<float>(oz_in[i]);
    dx[i] = static_cast<float>(dx_in[i]), dy[i] = static_cast<float>(dy_in[i]), dz[i] = static_cast<float>(dz_in[i]);
  }
  using F = float;
  F R[9], c[3];
  for (int k = 0; k < 9; ++k) R[k] = static_cast<F>(sh[k]);
  for (int k = 0; k < 3; ++k) c[k] = static_cast<F>(sh[9 + k]);
  const F lens_r2 = static_cast<F>(sh[12]), rim_z = static_cast<F>(sh[13]), rim_r2 = static_cast<F>(sh[14]);
  const F mount_r2 = static_cast<F>(sh[15]), half = static_cast<F>(sh[16]), length = static_cast<F>(sh[17]);
  const F inf = std::numeric_limits<F>::infinity();
  for (int i = 0; i < n; ++i) {
    const F o0 = ox[i], o1 = oy[i], o2 = oz[i], d0 = dx[i], d1 = dy[i], d2 = dz[i], tn = tnear[i];
    // The camera frame.
    const F cx = R[0] * o0 + R[3] * o1 + R[6] * o2 + c[0], cy = R[1] * o0 + R[4] * o1 + R[7] * o2 + c[1];
    const F cz = R[2] * o0 + R[5] * o1 + R[8] * o2 + c[2];
    const F ex = R[0] * d0 + R[3] * d1 + R[6] * d2, ey = R[1] * d0 + R[4] * d1 + R[7] * d2;
    const F ez = R[2] * d0 + R[5] * d1 + R[8] * d2;
    // The lens face: the disc z = 0 of the camera frame. (Flags as integers combined with &, and selects: the
    // loop then vectorises.)
    const F tl = -cz / ez, lx = cx + tl * ex, ly = cy + tl * ey;
    const int hl = (tl > tn ? 1 : 0) & (lx * lx + ly * ly <= lens_r2 ? 1 : 0);
    // The mount ring: the annulus in the rim plane.
    const F tm = (rim_z - o2) / d2, mx = o0 + tm * d0, my = o1 + tm * d1, mr2 = mx * mx + my * my;
    const int hm = (tm > tn ? 1 : 0) & (mr2 >= rim_r2 ? 1 : 0) & (mr2 <= mount_r2 ? 1 : 0);
    // The body: where the ray enters the box x, y in [-half, half], z in [-length, 0] of the camera frame.
    const F ix = F(1) / ex, iy = F(1) / ey, iz = F(1) / ez;
    const F ax = (-half - cx) * ix, bx = (half - cx) * ix, ay = (-half - cy) * iy, by = (half - cy) * iy;
    const F az = (-length - cz) * iz, bz = -cz * iz;
    const F nx = ax < bx ? ax : bx, fx = ax < bx ? bx : ax, ny = ay < by ? ay : by, fy = ay < by ? by : ay;
    const F nz = az < bz ? az : bz, fz = az < bz ? bz : az;
    const F nxy = nx < ny ? ny : nx, fxy = fx < fy ? fx : fy;
    const F enter = nxy < nz ? nz : nxy, exit = fxy < fz ? fxy : fz;
    const int hb = (enter <= exit ? 1 : 0) & (enter > tn ? 1 : 0);
    const int is_z = enter == nz ? 1 : 0, is_x = (enter == nx ? 1 : 0) & (1 - is_z);
    const int face = is_z * (ez < 0 ? 0 : 1) + is_x * (ex < 0 ? 2 : 3) + (1 - is_z - is_x) * (ey < 0 ? 4 : 5);
    // The nearest (the lens face first where the body's top face lies in its plane).
    F best = hl ? tl : inf;
    int p = hl;
    const int take_m = hm & (tm < best ? 1 : 0);
    p = take_m ? 2 : p;
    best = take_m ? tm : best;
    const int take_b = hb & (enter < best ? 1 : 0);
    p = take_b ? 3 + face : p;
    best = take_b ? enter : best;
    part[i] = active[i] != 0 ? p : 0;
    tout[i] = static_cast<float>(best);
  }
}

}  // namespace

template <class T>
bool RayScene::OwnParts(const RayBatchOf<T>& b, int U, BatchLanes* L, unsigned* own_geom, unsigned* own_prim) const {
  const MotionInstance& m = instances_[unit_instance_[U]];
  const OwnPartShapes& sh = m.own;
  const int n = b.n;
  alignas(64) unsigned char active[RayBatch::kMax];
  for (int i = 0; i < n; ++i) {
    // The unit's own rays skip its instance; those from its mirror meet its parts here. (Its straight camera
    // rays leave the lens face forwards: of its parts only the mount ring lies ahead, which PrepareLanes met.)
    const int from_mirror = b.from_mirror[i] == U ? 1 : 0, own = from_mirror | (b.from_camera[i] == U ? 1 : 0);
    L->mask_off[i] |= sh.mask & static_cast<unsigned>(-own);
    active[i] = static_cast<unsigned char>(from_mirror & (L->valid[i] != 0 ? 1 : 0));
  }
  alignas(64) T fo[6][RayBatch::kMax];
  const T *mox = b.mox, *moy = b.moy, *moz = b.moz, *mdx = b.mdx, *mdy = b.mdy, *mdz = b.mdz;
  if (!b.mirror_frame) {  // rays at time 0: the world rays mapped back
    RaysToFrame<T>(n, sh.R_mirror_from_world, sh.t_mirror_from_world, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, fo[0], fo[1],
                   fo[2], fo[3], fo[4], fo[5]);
    mox = fo[0], moy = fo[1], moz = fo[2], mdx = fo[3], mdy = fo[4], mdz = fo[5];
  }
  alignas(64) int part[RayBatch::kMax];
  alignas(64) float t[RayBatch::kMax];
  OwnPartLanes<T>(n, active, mox, moy, moz, mdx, mdy, mdz, b.tnear, sh.shape, part, t);
  bool any = false;
  for (int i = 0; i < n; ++i) {
    if (!part[i]) continue;
    any = true;
    L->tfar[i] = t[i];  // the world trace looks only nearer
    own_geom[i] = part[i] == 1 ? sh.lens_geom : part[i] == 2 ? sh.mount_geom : rect_geom_;
    own_prim[i] = part[i] >= 3 ? m.rect_base + static_cast<unsigned>(part[i] - 3) : 0u;
  }
  return any;
}

template <class T>
int RayScene::IntersectBatch(const RayBatchOf<T>& b, unsigned* geom_ids, unsigned* prim_ids) const {
  BatchLanes lanes;
  PrepareLanes(b, own_mount_, &lanes);
  // A moving unit's own rays meet its own parts in its mirror frame (OwnParts), not through its instance.
  alignas(64) unsigned own_geom[RayBatch::kMax], own_prim[RayBatch::kMax];
  bool own = false;
  if (!instances_.empty()) {
    int U = -1;
    for (int i = 0; i < b.n; ++i) U = std::max(U, std::max(b.from_mirror[i], b.from_camera[i]));
    if (OwnPartsInMirrorFrame(U)) {
      std::fill(own_geom, own_geom + b.n, RTC_INVALID_GEOMETRY_ID);
      own = OwnParts(b, U, &lanes, own_geom, own_prim);
    }
  }
  int traced = 0;  // lanes Embree traces (valid -1; 0: ended analytically, or invalid)
  for (int i = 0; i < b.n; ++i) traced -= lanes.valid[i];
  alignas(64) unsigned inst[RayBatch::kMax];
  unsigned* const inst_ids = instances_.empty() ? nullptr : inst;
  const float inv_horizon = static_cast<float>(1.0 / motion_horizon_);
  for (int i0 = 0; i0 < b.n; i0 += native16_ ? 16 : 8) {
    unsigned* const ii = inst_ids ? inst_ids + i0 : nullptr;
    if (native16_) {
      TracePacketOfBatch<16, RTCRayHit16>(scene_, b, lanes, i0, geom_ids + i0, prim_ids + i0, ii, inv_horizon,
                                          rtcIntersect16);
    } else {
      // Without native 16-wide packets (no AVX-512) Embree emulates rtcIntersect16; rtcIntersect8 is faster.
      TracePacketOfBatch<8, RTCRayHit8>(scene_, b, lanes, i0, geom_ids + i0, prim_ids + i0, ii, inv_horizon,
                                        rtcIntersect8);
    }
  }
  if (inst_ids) MapInstanceHits(b.n, inst_ids, geom_ids, prim_ids);
  ResolveMisses(b.n, lanes.mount_geom, geom_ids, prim_ids);
  if (own) {  // nothing in the world nearer than the unit's own part: the part
    for (int i = 0; i < b.n; ++i) {
      if (own_geom[i] == RTC_INVALID_GEOMETRY_ID || geom_ids[i] != RTC_INVALID_GEOMETRY_ID) continue;
      geom_ids[i] = own_geom[i], prim_ids[i] = own_prim[i];
    }
  }
  return traced;
}

// ColoursOf and Geometry (shading.cc) intersect both batch kinds.
template int RayScene::IntersectBatch<double>(const RayBatchOf<double>&, unsigned*, unsigned*) const;
template int RayScene::IntersectBatch<float>(const RayBatchOf<float>&, unsigned*, unsigned*) const;

Hit RayScene::Trace(const Vec3d& origin, const Vec3d& direction, double tnear, int from_mirror) const {
  Hit h;
  Trace16(1, &origin, &direction, &tnear, &h, &from_mirror);
  return h;
}

bool RayScene::Occluded(const Vec3d& a, const Vec3d& b, double eps) const {
  const Vec3d seg = b - a;
  const double len = seg.norm();
  if (len <= 2 * eps) return false;
  const Vec3d d = seg / len;
  RTCRay ray;
  ray.org_x = static_cast<float>(a.x()), ray.org_y = static_cast<float>(a.y()), ray.org_z = static_cast<float>(a.z());
  ray.dir_x = static_cast<float>(d.x()), ray.dir_y = static_cast<float>(d.y()), ray.dir_z = static_cast<float>(d.z());
  ray.tnear = static_cast<float>(eps);
  ray.tfar = static_cast<float>(len - eps);
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  ray.time = 0;
  ray.id = 0;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded1(scene_, &ctx, &ray);
  return ray.tfar < 0;
}

void RayScene::IntersectOnly16(int count, const Vec3d* o, const Vec3d* d, unsigned* geom_ids,
                               const int* from_mirror) const {
  alignas(64) RTCRayHit16 rh;
  IntersectPacket(scene_, count, o, d, nullptr, from_mirror, &rh);
  if (!instances_.empty()) MapInstanceHits(count, rh.hit.instID[0], rh.hit.geomID, rh.hit.primID);
  for (int i = 0; i < count; ++i) geom_ids[i] = rh.hit.geomID[i];
}

namespace {
// Lanes [i0, i0 + W) of a raw packet into an Embree packet of width W, every lane valid. (SetLane's fields with
// the mask and id computed once: with SetLane per lane the raw figure was about 6 % slower.)
template <int W, class RayHitW>
void FillRawPacket(const RayScene::RawPacket16& p, int i0, unsigned mask, unsigned id, int* valid, RayHitW* rh) {
  for (int i = 0; i < W; ++i) {
    valid[i] = -1;
    rh->ray.org_x[i] = p.ox[i0 + i], rh->ray.org_y[i] = p.oy[i0 + i], rh->ray.org_z[i] = p.oz[i0 + i];
    rh->ray.dir_x[i] = p.dx[i0 + i], rh->ray.dir_y[i] = p.dy[i0 + i], rh->ray.dir_z[i] = p.dz[i0 + i];
    rh->ray.tnear[i] = 0, rh->ray.tfar[i] = std::numeric_limits<float>::infinity();
    rh->ray.mask[i] = mask, rh->ray.id[i] = id, rh->ray.flags[i] = 0, rh->ray.time[i] = 0;
    rh->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID, rh->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
  }
}
}  // namespace

void RayScene::IntersectRaw(const RawPacket16& p, int from_mirror, int width, unsigned* geom_ids) const {
  const unsigned mask = RayMask(from_mirror), id = static_cast<unsigned>(std::max(from_mirror, -1) + 1);
  if (width == 16) {
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    FillRawPacket<16>(p, 0, mask, id, valid, &rh);
    TracePacket(scene_, valid, &rh, rtcIntersect16);
    for (int i = 0; i < 16; ++i) geom_ids[i] = rh.hit.geomID[i];
    return;
  }
  HOVS_REQUIRE(width == 8, "IntersectRaw", "width must be 8 or 16 (got ", width, ")");
  for (int i0 = 0; i0 < 16; i0 += 8) {
    alignas(32) RTCRayHit8 rh;
    alignas(32) int valid[8];
    FillRawPacket<8>(p, i0, mask, id, valid, &rh);
    TracePacket(scene_, valid, &rh, rtcIntersect8);
    for (int i = 0; i < 8; ++i) geom_ids[i0 + i] = rh.hit.geomID[i];
  }
}

}  // namespace hovs::raytrace
