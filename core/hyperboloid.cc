#include "core/hyperboloid.h"

#include <algorithm>
#include <limits>

#include "core/vector_clones.h"

namespace hovs {
namespace {

// The loop of MirrorReflector::ReflectBatch: IntersectSheetWith, the rim test and ReflectAt with the origin's
// terms hoisted, as selects instead of branches. Lanes whose quadratic degenerates (|A| tiny, a ray almost
// parallel to the asymptotic cone) are marked 2 and solved again by the caller with the scalar code.
HOVS_VECTOR_CLONES
void ReflectKernel(double cc, double ia2, double ib2, double rim2, double o0, double o1, double o2, int n,
                   const double* __restrict vx, const double* __restrict vy, const double* __restrict vz,
                   double* __restrict Mx, double* __restrict My, double* __restrict Mz, double* __restrict dx,
                   double* __restrict dy, double* __restrict dz, double* __restrict ok) {
  const double inf = std::numeric_limits<double>::infinity();
  const double oz = o2 + cc;
  const double C = oz * oz * ia2 - (o0 * o0 + o1 * o1) * ib2 - 1.0;
  for (int i = 0; i < n; ++i) {
    const double v0 = vx[i], v1 = vy[i], v2 = vz[i];
    const double A = v2 * v2 * ia2 - (v0 * v0 + v1 * v1) * ib2;
    const double B = oz * v2 * ia2 - (o0 * v0 + o1 * v1) * ib2;
    const double absA = A < 0 ? -A : A, absB = B < 0 ? -B : B;
    const double degenerate = absA < 1e-14 * (absB + absA + 1e-300) ? 2.0 : 0.0;
    const double disc = B * B - A * C;
    const double sq = std::sqrt(disc >= 0 ? disc : 0.0);
    const double q = B >= 0 ? -(B + sq) : -(B - sq);
    // As IntersectSheetWith: both roots from one division; q = 0 gives no valid root either way (inv infinite,
    // r1 = 0 * inf is NaN, t0 is set to inf below).
    const double inv = 1.0 / (q * A);
    const double r0 = C * A * inv, r1 = q * q * inv;
    // The smaller valid root (r0 on a tie, as the scalar loop), +inf when neither is valid (t > 0, finite, on
    // the upper sheet). Written as chains of single-comparison selects on doubles, which GCC 12 vectorises (it
    // does not vectorise && or & of comparisons here).
    const double z0 = (o2 + r0 * v2) + cc, z1 = (o2 + r1 * v2) + cc;
    double t0 = q != 0 ? r0 : inf;
    t0 = t0 > 0 ? t0 : inf;
    t0 = z0 > 0 ? t0 : inf;
    double t1 = r1 > 0 ? r1 : inf;
    t1 = z1 > 0 ? t1 : inf;
    const double t = t1 < t0 ? t1 : t0;
    const double M0 = o0 + t * v0, M1 = o1 + t * v1, M2 = o2 + t * v2;
    double hit = disc >= 0 ? 1.0 : 0.0;
    hit = t < inf ? hit : 0.0;
    hit = M0 * M0 + M1 * M1 <= rim2 ? hit : 0.0;
    // ReflectAt, inline.
    const double n0 = M0 * ib2, n1 = M1 * ib2, n2 = -(M2 + cc) * ia2;
    const double nn = n0 * n0 + n1 * n1 + n2 * n2, vlen = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
    const double g = 1.0 / (nn * vlen);
    const double k = 2 * (v0 * n0 + v1 * n1 + v2 * n2) * (g * vlen);
    const double w0 = v0 - k * n0, w1 = v1 - k * n1, w2 = v2 - k * n2;
    const double inv_len = g * nn;
    Mx[i] = M0, My[i] = M1, Mz[i] = M2;
    dx[i] = w0 * inv_len, dy[i] = w1 * inv_len, dz[i] = w2 * inv_len;
    ok[i] = degenerate > hit ? degenerate : hit;
  }
}

// The count of rays that go up and cross the plane z = zr (from o, which lies below it) within radius^2 lim,
// without a division: |o_xy vz + (zr - oz) v_xy|^2 <= lim vz^2.
HOVS_VECTOR_CLONES
int CountRimCrossings(double o0, double o1, double dz, double lim, int n, const double* __restrict vx,
                      const double* __restrict vy, const double* __restrict vz) {
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const double px = o0 * vz[i] + dz * vx[i], py = o1 * vz[i] + dz * vy[i];
    const int inside = px * px + py * py <= lim * (vz[i] * vz[i]) ? 1 : 0;
    count += vz[i] > 0 ? inside : 0;
  }
  return count;
}

}  // namespace

bool MirrorReflector::MissesRim(const Vec3d& o, int n, const double* vx, const double* vy, const double* vz) const {
  const double oz = o(2) + c_;
  const bool in_lower_nappe = oz < 0 && oz * oz * ia2_ - (o(0) * o(0) + o(1) * o(1)) * ib2_ >= 1 && o(2) < rim_z_;
  if (!in_lower_nappe) return false;
  if (n == 0) return true;
  // Ray 0 first: inside the rim usually means a block to solve, answered without the pass over all rays.
  const double lim = rim2_ * (1 + 1e-6);
  return CountRimCrossings(o(0), o(1), rim_z_ - o(2), lim, 1, vx, vy, vz) == 0 &&
         CountRimCrossings(o(0), o(1), rim_z_ - o(2), lim, n, vx, vy, vz) == 0;
}

void MirrorReflector::ReflectBatch(const Vec3d& o, int n, const double* vx, const double* vy, const double* vz,
                                   double* Mx, double* My, double* Mz, double* dx, double* dy, double* dz,
                                   unsigned char* ok) const {
  // In blocks, with the lane flags as doubles (a byte array among doubles stops GCC 12's vectoriser).
  constexpr int kBlock = 64;
  double flag[kBlock];
  for (int i0 = 0; i0 < n; i0 += kBlock) {
    const int m = std::min(kBlock, n - i0);
    if (MissesRim(o, m, vx + i0, vy + i0, vz + i0)) {
      for (double* a : {Mx, My, Mz, dx, dy, dz}) std::fill(a + i0, a + i0 + m, 0.0);
      std::fill(ok + i0, ok + i0 + m, 0);
      continue;
    }
    ReflectKernel(c_, ia2_, ib2_, rim2_, o(0), o(1), o(2), m, vx + i0, vy + i0, vz + i0, Mx + i0, My + i0, Mz + i0,
                  dx + i0, dy + i0, dz + i0, flag);
    double most = 0;
    for (int i = 0; i < m; ++i) {
      ok[i0 + i] = static_cast<unsigned char>(flag[i]);
      most = flag[i] > most ? flag[i] : most;
    }
    if (most < 2) continue;
    for (int i = i0; i < i0 + m; ++i) {   // degenerate lanes (flag 2): the scalar solve
      if (ok[i] != 2) continue;
      Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
      ok[i] = Reflect(o, Vec3d(vx[i], vy[i], vz[i]), &M, &d) ? 1 : 0;
      Mx[i] = M(0), My[i] = M(1), Mz[i] = M(2), dx[i] = d(0), dy[i] = d(1), dz[i] = d(2);
    }
  }
}

}  // namespace hovs
