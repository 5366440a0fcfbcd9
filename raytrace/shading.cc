#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/error.h"
#include "core/vector_clones.h"
#include "raytrace/scene_internal.h"

namespace hovs::raytrace {
using namespace internal;

void RayScene::Shade(const Vec3d& o, const Vec3d& d, unsigned geom_id, unsigned prim_id, Hit* h, bool colour) const {
  if (geom_id == rect_geom_) {
    const Rect& r = desc_.rects[prim_id];
    const RectFrame& fr = rect_frames_[prim_id];
    const Vec3d& n = fr.normal;
    const double denom = d.dot(n);
    if (denom == 0) return;
    const double t = (fr.centre - o).dot(n) / denom;
    const Vec3d X = o + t * d;
    const Vec2d local(fr.axis_x.dot(X - fr.centre), fr.axis_y.dot(X - fr.centre));
    const bool front = denom < 0;
    h->hit = true;
    h->object_id = r.object_id;
    h->t = t;
    h->point = X;
    h->normal = front ? n : Vec3d(-n);
    if (colour) h->colour = front || r.double_sided ? r.front.Eval(local.x(), local.y()) : r.back;
    return;
  }
  if (geom_id >= geom_to_user_.size() || geom_to_user_[geom_id] < 0) return;
  const UserGeometry& g = *user_[geom_to_user_[geom_id]];
  double t = 0;
  Vec3d n;
  if (!g.Intersect(o, d, 0.0, HUGE_VAL, &t, &n)) {
    // Embree's float ray and the double ray disagree at a silhouette: take the float distance.
    n = Vec3d(0, 0, 1);
  }
  UserHit(g, o, d, t, n, h);
  (void)prim_id;
}

void RayScene::UserHit(const UserGeometry& g, const Vec3d& o, const Vec3d& d, double t, const Vec3d& n, Hit* h) {
  h->hit = true;
  h->object_id = g.object_id;
  h->unit = g.unit;
  h->t = t;
  h->point = o + t * d;
  h->normal = d.dot(n) < 0 ? n : Vec3d(-n);
  h->colour = g.kind == UserGeometry::Kind::kMirror ? g.back_colour : g.colour;
}

namespace {

// Where batch rays i0 .. i0 + m - 1 meet a rectangle's plane, into the same lanes of out: d.n, the distance k
// along d, the point p = o + k d and its (s, t) on the rectangle, axis_x.(p - c) and axis_y.(p - c): the
// operations of the scalar Eigen expressions (Shade; 3-vector dot products sum left to right). f: the
// rectangle's centre c, normal, axis_x, axis_y (RectFrame::flat).
template <class T>
struct RectPlaneRuns {
  alignas(64) T denom[RayBatch::kMax], k[RayBatch::kMax], px[RayBatch::kMax], py[RayBatch::kMax], pz[RayBatch::kMax],
      s[RayBatch::kMax], t[RayBatch::kMax];
};
template <class T>
HOVS_VECTOR_CLONES void RectPlaneHits(int i0, int m, const T* __restrict ox, const T* __restrict oy,
                                      const T* __restrict oz, const T* __restrict dx, const T* __restrict dy,
                                      const T* __restrict dz, const T* __restrict f, RectPlaneRuns<T>* __restrict out) {
  const T cx = f[0], cy = f[1], cz = f[2], nx = f[3], ny = f[4], nz = f[5];
  const T ax = f[6], ay = f[7], az = f[8], bx = f[9], by = f[10], bz = f[11];
  for (int i = i0; i < i0 + m; ++i) {
    const T dn = dx[i] * nx + dy[i] * ny + dz[i] * nz;
    const T k = ((cx - ox[i]) * nx + (cy - oy[i]) * ny + (cz - oz[i]) * nz) / dn;
    const T px = ox[i] + k * dx[i], py = oy[i] + k * dy[i], pz = oz[i] + k * dz[i];
    const T X0 = px - cx, X1 = py - cy, X2 = pz - cz;
    out->denom[i] = dn, out->k[i] = k, out->px[i] = px, out->py[i] = py, out->pz[i] = pz;
    out->s[i] = ax * X0 + ay * X1 + az * X2;
    out->t[i] = bx * X0 + by * X1 + bz * X2;
  }
}

// The sky colour (Sky::Eval) of rays [0, m) from their directions' z, into rgb (3 floats per ray).
template <class T>
HOVS_VECTOR_CLONES void SkyColours(int m, const T* __restrict dz, const float* __restrict horizon,
                                   const float* __restrict zenith, const float* __restrict nadir,
                                   float* __restrict rgb) {
  for (int i = 0; i < m; ++i) {
    const T z = std::clamp(dz[i], T(-1), T(1));
    const bool up = z >= 0;
    const float f = static_cast<float>(std::sqrt(up ? z : -z));
    for (int c = 0; c < 3; ++c) {
      const float a = horizon[c], e = up ? zenith[c] : nadir[c];
      rgb[3 * i + c] = a + f * (e - a);
    }
  }
}

// n copies of colour c, interleaved (rgb[3 k + ch]), 16 at a time from a pattern.
void FillColour(int n, const Rgb& c, float* rgb) {
  float pattern[48];
  for (int k = 0; k < 16; ++k) pattern[3 * k] = c[0], pattern[3 * k + 1] = c[1], pattern[3 * k + 2] = c[2];
  int k = 0;
  for (; k + 16 <= n; k += 16) std::memcpy(rgb + 3 * k, pattern, sizeof pattern);
  std::memcpy(rgb + 3 * k, pattern, sizeof(float) * 3 * static_cast<size_t>(n - k));
}

}  // namespace

namespace {

// Where the lanes of a batch change: brk[k] = 1 where lane k differs from lane k - 1 in validity, geometry or
// primitive (brk[0] = 1), and brk[n] = 1 as a sentinel; vectorised. RunEnd then finds the end of the run that
// starts at lane i with memchr (SIMD in glibc) instead of a scalar loop of three loads and compares per lane.
struct RunBreaks {
  unsigned char brk[RayBatch::kMax + 1];
};
HOVS_VECTOR_CLONES void FindRunBreaks(int n, const unsigned char* __restrict valid, const unsigned* __restrict geom,
                                      const unsigned* __restrict prim, unsigned char* __restrict brk) {
  // In blocks of a constant 32 lanes (the last one overlapping the one before: the same values again), so that
  // the loop is vectorised without a scalar remainder.
  constexpr int kB = 32;
  const auto block = [&](int k0) {
    for (int k = k0; k < k0 + kB; ++k) {
      const int differ = (valid[k] != valid[k - 1]) | (geom[k] != geom[k - 1]) | (prim[k] != prim[k - 1]);
      brk[k] = static_cast<unsigned char>(differ);
    }
  };
  brk[0] = 1;
  if (n > kB) {
    for (int k0 = 1; k0 < n; k0 += kB) block(std::min(k0, n - kB));
  } else {
    for (int k = 1; k < n; ++k) {
      const int differ = (valid[k] != valid[k - 1]) | (geom[k] != geom[k - 1]) | (prim[k] != prim[k - 1]);
      brk[k] = static_cast<unsigned char>(differ);
    }
  }
  brk[n] = 1;
}
// The first lane after i that starts a new run (n at most).
inline int RunEnd(const RunBreaks& r, int i) {
  return static_cast<int>(static_cast<const unsigned char*>(std::memchr(r.brk + i + 1, 1, sizeof r.brk - (i + 1))) -
                          r.brk);
}

}  // namespace

int RayScene::Colours(const RayBatch& b, float* rgb) const { return ColoursOf(b, rgb); }
int RayScene::Colours(const RayBatchF& b, float* rgb) const { return ColoursOf(b, rgb); }

template <class T>
int RayScene::ColoursOf(const RayBatchOf<T>& b, float* rgb) const {
  const int n = b.n;
  unsigned geom[RayBatch::kMax], prim[RayBatch::kMax];
  const int traced = IntersectBatch(b, geom, prim);
  // Runs of consecutive lanes on the sky, or on one rectangle, are evaluated together (vectorised); hits with a
  // noise texture in short runs (or runs with lanes that see the back) are collected per rectangle and evaluated
  // together.
  constexpr int kShortNoiseRun = 16;
  int deferred[RayBatch::kMax], n_deferred = 0;
  const auto put = [&](int i, const Rgb& c) { rgb[3 * i] = c[0], rgb[3 * i + 1] = c[1], rgb[3 * i + 2] = c[2]; };
  RectPlaneRuns<T> planes;
  const T *s_at = planes.s, *t_at = planes.t, *denom = planes.denom;
  RunBreaks runs;
  FindRunBreaks(n, b.valid, geom, prim, runs.brk);
  for (int i = 0; i < n;) {
    const unsigned g = geom[i];
    if (!b.valid[i]) {
      put(i++, {0, 0, 0});
      continue;
    }
    // The run of lanes like lane i (valid, the same geometry and primitive; misses and the lanes of an analytic
    // shape have primitive 0).
    const int j = RunEnd(runs, i);
    if (g == RTC_INVALID_GEOMETRY_ID) {
      SkyColours(j - i, b.dz + i, desc_.sky.horizon.data(), desc_.sky.zenith.data(), desc_.sky.nadir.data(),
                 rgb + 3 * i);
    } else if (g == rect_geom_) {
      const unsigned p = prim[i];
      const RectFrame& fr = rect_frames_[p];
      const T* flat;
      if constexpr (std::is_same_v<T, float>)
        flat = fr.flat_f;
      else
        flat = fr.flat;
      RectPlaneHits<T>(i, j - i, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, flat, &planes);
      const Rect& r = desc_.rects[p];
      const bool noise = r.front.kind == Texture::Kind::kNoise, double_sided = r.double_sided;
      // Edge-on: no hit (as Shade); the back of a single-sided rectangle: its back colour.
      // (In integers, without branches: the count below vectorises.)
      const int ds = double_sided ? 1 : 0;
      const auto seen = [&](int k) {
        const int nonzero = denom[k] != 0 ? 1 : 0, not_facing_away = denom[k] > 0 ? 0 : 1;
        return nonzero & (not_facing_away | ds);
      };
      int front = 0;
      for (int k = i; k < j; ++k) front += seen(k);
      if (front == j - i && (!noise || j - i >= kShortNoiseRun)) {
        r.front.EvalInto(j - i, s_at + i, t_at + i, rgb + 3 * i);
      } else if (noise) {
        int nd = n_deferred;
        for (int k = i; k < j; ++k) {  // without branches: the lane is kept when seen
          const int keep = seen(k);
          deferred[nd] = k, nd += keep;
        }
        n_deferred = nd;
      } else {
        for (int k = i; k < j; ++k)
          if (seen(k)) put(k, r.front.Eval(s_at[k], t_at[k]));
      }
      if (front < j - i)
        for (int k = i; k < j; ++k)
          if (!seen(k)) put(k, denom[k] == 0 ? Rgb{0, 0, 0} : r.back);
    } else if (g < geom_to_user_.size() && geom_to_user_[g] >= 0) {
      // A run of lanes on one analytic shape (the mount ring past the rim: long runs): one flat colour.
      const UserGeometry& u = *user_[geom_to_user_[g]];
      const Rgb& c = u.kind == UserGeometry::Kind::kMirror ? u.back_colour : u.colour;
      FillColour(j - i, c, rgb + 3 * i);
    } else {
      for (int k = i; k < j; ++k) put(k, {0, 0, 0});
    }
    i = j;
  }
  // The noise: one batch per rectangle, in order of first appearance (usually one: the floor). Each pass takes
  // the rays of the first rectangle left and keeps the others, in order, for the next.
  T s_batch[RayBatch::kMax], t_batch[RayBatch::kMax];
  int lanes[RayBatch::kMax];
  float colours[3 * RayBatch::kMax];
  for (int left = n_deferred; left > 0;) {
    const unsigned p = prim[deferred[0]];
    int m = 0, kept = 0;
    for (int k = 0; k < left; ++k) {
      const int i = deferred[k];
      if (prim[i] == p) {
        lanes[m] = i, s_batch[m] = s_at[i], t_batch[m] = t_at[i], ++m;
      } else {
        deferred[kept++] = i;
      }
    }
    desc_.rects[p].front.EvalInto(m, s_batch, t_batch, colours);
    for (int k = 0; k < m; ++k) put(lanes[k], {colours[3 * k], colours[3 * k + 1], colours[3 * k + 2]});
    left = kept;
  }
  return traced;
}

namespace {

// Lanes [i0, i1) of a run on one rectangle into the hits, from their plane points (RectPlaneHits): a hit unless
// the ray is parallel to the plane (denom 0), with the normal facing the ray (as Shade).
HOVS_VECTOR_CLONES
void RectHitLanes(int i0, int i1, const RectPlaneRuns<double>* __restrict planes, const double* __restrict normal,
                  int id, HitBatch* __restrict H) {
  const double n0 = normal[0], n1 = normal[1], n2 = normal[2];
  for (int k = i0; k < i1; ++k) {
    const bool hit = planes->denom[k] != 0;
    const double s = planes->denom[k] < 0 ? 1.0 : -1.0;
    H->hit[k] = hit ? 1 : 0;
    H->object_id[k] = hit ? id : static_cast<int>(kSkyId);
    // (Selects, not products: a ray parallel to the plane has an infinite distance and no finite point.)
    H->px[k] = hit ? planes->px[k] : 0.0, H->py[k] = hit ? planes->py[k] : 0.0, H->pz[k] = hit ? planes->pz[k] : 0.0;
    H->nx[k] = hit ? s * n0 : 0.0, H->ny[k] = hit ? s * n1 : 0.0, H->nz[k] = hit ? s * n2 : 0.0;
  }
}

// Lanes [i0, i1) of straight camera rays ending on their mount ring at distance t[k] (the renderer's analytic
// test): the point o + t d and the ring's normal n facing the ray (as UserHit).
HOVS_VECTOR_CLONES
void RingHitLanes(int i0, int i1, const double* __restrict ox, const double* __restrict oy, const double* __restrict oz,
                  const double* __restrict dx, const double* __restrict dy, const double* __restrict dz,
                  const double* __restrict t, const double* __restrict normal, int id, HitBatch* __restrict H) {
  const double n0 = normal[0], n1 = normal[1], n2 = normal[2];
  for (int k = i0; k < i1; ++k) {
    const double s = dx[k] * n0 + dy[k] * n1 + dz[k] * n2 < 0 ? 1.0 : -1.0;
    H->hit[k] = 1;
    H->object_id[k] = id;
    H->px[k] = ox[k] + t[k] * dx[k], H->py[k] = oy[k] + t[k] * dy[k], H->pz[k] = oz[k] + t[k] * dz[k];
    H->nx[k] = s * n0, H->ny[k] = s * n1, H->nz[k] = s * n2;
  }
}

}  // namespace

int RayScene::Geometry(const RayBatch& b, HitBatch* H) const {
  unsigned geom[RayBatch::kMax], prim[RayBatch::kMax];
  const int traced = IntersectBatch(b, geom, prim);
  RectPlaneRuns<double> planes;
  // Lane k ends on its unit's mount ring at the renderer's analytic distance: the unit, else -1.
  const auto ring_unit = [&](int k) {
    const int u = b.from_camera[k];
    return b.valid[k] && u >= 0 && static_cast<size_t>(u) < own_mount_.size() && own_mount_[u].geometry &&
                   b.mount_t[k] > 0 && geom[k] == own_mount_[u].geom_id
               ? u
               : -1;
  };
  RunBreaks runs;
  FindRunBreaks(b.n, b.valid, geom, prim, runs.brk);
  for (int i = 0; i < b.n;) {
    int j = i + 1;
    if (b.valid[i] && geom[i] == rect_geom_) {
      // A run of consecutive lanes on one rectangle: their plane points in one vectorised pass (as Shade).
      const unsigned p = prim[i];
      j = RunEnd(runs, i);
      const RectFrame& fr = rect_frames_[p];
      RectPlaneHits<double>(i, j - i, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, fr.flat, &planes);
      RectHitLanes(i, j, &planes, fr.normal.data(), desc_.rects[p].object_id, H);
      i = j;
      continue;
    }
    if (const int u = ring_unit(i); u >= 0) {
      // A run of straight camera rays that ended on their own mount ring: the ring's distance is already known
      // (in double); Shade would solve it again. The ring's normal is its local z.
      // Usually the whole run of lanes on the ring geometry is the camera's straight rays: tested in one pass
      // over the run, else lane by lane.
      const int e = RunEnd(runs, i);
      int straight = 0;
      for (int k = i; k < e; ++k) straight += (b.from_camera[k] == u ? 1 : 0) & (b.mount_t[k] > 0 ? 1 : 0);
      if (straight == e - i) {
        j = e;
      } else {
        while (j < b.n && ring_unit(j) == u) ++j;
      }
      const UserGeometry& g = *own_mount_[u].geometry;
      const Vec3d n = g.R_world_from_local.col(2);
      RingHitLanes(i, j, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, b.mount_t, n.data(), g.object_id, H);
      i = j;
      continue;
    }
    Hit h;
    if (b.valid[i] && geom[i] != RTC_INVALID_GEOMETRY_ID)
      Shade(Vec3d(b.ox[i], b.oy[i], b.oz[i]), Vec3d(b.dx[i], b.dy[i], b.dz[i]), geom[i], prim[i], &h, false);
    H->hit[i] = h.hit ? 1 : 0;
    H->object_id[i] = h.object_id;
    H->px[i] = h.point.x(), H->py[i] = h.point.y(), H->pz[i] = h.point.z();
    H->nx[i] = h.normal.x(), H->ny[i] = h.normal.y(), H->nz[i] = h.normal.z();
    i = j;
  }
  return traced;
}

}  // namespace hovs::raytrace
