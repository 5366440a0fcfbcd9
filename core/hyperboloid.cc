#include "core/hyperboloid.h"

#include <algorithm>
#include <limits>

#include "core/vector_clones.h"

namespace hovs {
namespace {

// The loop of MirrorReflector::ReflectBatch: IntersectSheetWith, the rim test and ReflectAt with the origin's
// terms hoisted, as selects instead of branches, in T = double (to the bit as Reflect) or T = float (16 lanes
// of AVX-512 instead of 8: the renderer's colour samples). Lanes whose quadratic degenerates (|A| tiny against
// |B|, a ray almost parallel to the asymptotic cone; tiny means below kDegenerate, 1e-14 in double and 1e-6 in
// single precision) are marked 2 and solved again by the caller with the scalar code. The origin's terms (oz =
// o_z + c and C, the quadratic's constant) come from the caller, computed in double.
template <class T>
struct KernelLimits;
template <>
struct KernelLimits<double> {
  static constexpr double kDegenerate = 1e-14, kTiny = 1e-300;
};
template <>
struct KernelLimits<float> {
  static constexpr float kDegenerate = 1e-6f, kTiny = 1e-30f;
};

// One lane of the kernels below: IntersectSheetWith (origin o, its oz = o_z + c and the quadratic's constant C
// given), the rim test and ReflectAt. Writes M, d and the lane's flag (0 miss, 1 hit, 2 degenerate).
template <class T>
__attribute__((always_inline)) inline void ReflectLane(T cc, T ia2, T ib2, T rim2, T o0, T o1, T o2, T oz, T C, T v0,
                                                       T v1, T v2, T* M0_out, T* M1_out, T* M2_out, T* d0, T* d1, T* d2,
                                                       T* flag) {
  const T inf = std::numeric_limits<T>::infinity(), zero = 0, one = 1, two = 2;
  const T A = v2 * v2 * ia2 - (v0 * v0 + v1 * v1) * ib2;
  const T B = oz * v2 * ia2 - (o0 * v0 + o1 * v1) * ib2;
  const T absA = A < 0 ? -A : A, absB = B < 0 ? -B : B;
  const T degenerate = absA < KernelLimits<T>::kDegenerate * (absB + absA + KernelLimits<T>::kTiny) ? two : zero;
  const T disc = B * B - A * C;
  const T sq = std::sqrt(disc >= 0 ? disc : zero);
  const T q = B >= 0 ? -(B + sq) : -(B - sq);
  // As IntersectSheetWith: both roots from one division; q = 0 gives no valid root either way (inv infinite,
  // r1 = 0 * inf is NaN, t0 is set to inf below).
  const T inv = one / (q * A);
  const T r0 = C * A * inv, r1 = q * q * inv;
  // The smaller valid root (r0 on a tie, as the scalar loop), +inf when neither is valid (t > 0, finite, on
  // the upper sheet). Written as chains of single-comparison selects, which GCC 12 vectorises (it does not
  // vectorise && or & of comparisons here).
  const T z0 = (o2 + r0 * v2) + cc, z1 = (o2 + r1 * v2) + cc;
  T t0 = q != 0 ? r0 : inf;
  t0 = t0 > 0 ? t0 : inf;
  t0 = z0 > 0 ? t0 : inf;
  T t1 = r1 > 0 ? r1 : inf;
  t1 = z1 > 0 ? t1 : inf;
  const T t = t1 < t0 ? t1 : t0;
  const T M0 = o0 + t * v0, M1 = o1 + t * v1, M2 = o2 + t * v2;
  T hit = disc >= 0 ? one : zero;
  hit = t < inf ? hit : zero;
  hit = M0 * M0 + M1 * M1 <= rim2 ? hit : zero;
  // ReflectAt, inline.
  const T n0 = M0 * ib2, n1 = M1 * ib2, n2 = -(M2 + cc) * ia2;
  const T nn = n0 * n0 + n1 * n1 + n2 * n2, vlen = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
  const T g = one / (nn * vlen);
  const T k = two * (v0 * n0 + v1 * n1 + v2 * n2) * (g * vlen);
  const T w0 = v0 - k * n0, w1 = v1 - k * n1, w2 = v2 - k * n2;
  const T inv_len = g * nn;
  *M0_out = M0, *M1_out = M1, *M2_out = M2;
  *d0 = w0 * inv_len, *d1 = w1 * inv_len, *d2 = w2 * inv_len;
  *flag = degenerate > hit ? degenerate : hit;
}

template <class T>
HOVS_VECTOR_CLONES void ReflectKernel(T cc, T ia2, T ib2, T rim2, T o0, T o1, T o2, T oz, T C, int n,
                                      const T* __restrict vx, const T* __restrict vy, const T* __restrict vz,
                                      T* __restrict Mx, T* __restrict My, T* __restrict Mz, T* __restrict dx,
                                      T* __restrict dy, T* __restrict dz, T* __restrict ok) {
  for (int i = 0; i < n; ++i)
    ReflectLane<T>(cc, ia2, ib2, rim2, o0, o1, o2, oz, C, vx[i], vy[i], vz[i], Mx + i, My + i, Mz + i, dx + i, dy + i,
                   dz + i, ok + i);
}

// ReflectKernel with an origin per ray (thin-lens samples leave points of the aperture), in double: oz and C per
// lane as IntersectSheetWith computes them.
HOVS_VECTOR_CLONES void ReflectRaysKernel(double cc, double ia2, double ib2, double rim2, int n,
                                          const double* __restrict ox, const double* __restrict oy,
                                          const double* __restrict oz_in, const double* __restrict vx,
                                          const double* __restrict vy, const double* __restrict vz,
                                          double* __restrict Mx, double* __restrict My, double* __restrict Mz,
                                          double* __restrict dx, double* __restrict dy, double* __restrict dz,
                                          double* __restrict ok) {
  for (int i = 0; i < n; ++i) {
    const double o0 = ox[i], o1 = oy[i], o2 = oz_in[i];
    const double oz = o2 + cc;
    const double C = oz * oz * ia2 - (o0 * o0 + o1 * o1) * ib2 - 1.0;
    ReflectLane<double>(cc, ia2, ib2, rim2, o0, o1, o2, oz, C, vx[i], vy[i], vz[i], Mx + i, My + i, Mz + i, dx + i,
                        dy + i, dz + i, ok + i);
  }
}

// The count of rays that go up and cross the plane z = zr (from o, which lies below it) within radius^2 lim,
// without a division: |o_xy vz + (zr - oz) v_xy|^2 <= lim vz^2.
template <class T>
HOVS_VECTOR_CLONES int CountRimCrossings(T o0, T o1, T dz, T lim, int n, const T* __restrict vx, const T* __restrict vy,
                                         const T* __restrict vz) {
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const T px = o0 * vz[i] + dz * vx[i], py = o1 * vz[i] + dz * vy[i];
    const int inside = px * px + py * py <= lim * (vz[i] * vz[i]) ? 1 : 0;
    count += vz[i] > 0 ? inside : 0;
  }
  return count;
}

// The kernel's lane flags (0, 1 or 2) as bytes into ok, and how many are 1 (*hits); returns the largest flag.
// (In integers: GCC vectorises integer reductions, not a floating-point maximum.)
template <class T>
HOVS_VECTOR_CLONES int StoreLaneFlags(int n, const T* __restrict flag, unsigned char* __restrict ok, int* hits) {
  int most = 0, count = 0;
  for (int i = 0; i < n; ++i) {
    const int f = static_cast<int>(flag[i]);
    ok[i] = static_cast<unsigned char>(f);
    most = std::max(most, f);
    count += f == 1 ? 1 : 0;
  }
  *hits += count;
  return most;
}

// The lanes of a block that misses the rim: zero (the caller's z, 0: a value GCC cannot see, or it turns the
// loop into seven memset calls or rep stos, slow for 64 lanes; so vector stores).
template <class T>
HOVS_VECTOR_CLONES void ZeroLanes(int m, T z, T* __restrict Mx, T* __restrict My, T* __restrict Mz, T* __restrict dx,
                                  T* __restrict dy, T* __restrict dz, unsigned char* __restrict ok) {
  const unsigned char zb = z != 0 ? 1 : 0;
  for (int i = 0; i < m; ++i) {
    Mx[i] = z, My[i] = z, Mz[i] = z, dx[i] = z, dy[i] = z, dz[i] = z;
    ok[i] = zb;
  }
}

}  // namespace

template <class T>
bool MirrorReflector::MissesRimOf(const Vec3d& o, int n, const T* vx, const T* vy, const T* vz) const {
  const double oz = o(2) + c_;
  const bool in_lower_nappe = oz < 0 && oz * oz * ia2_ - (o(0) * o(0) + o(1) * o(1)) * ib2_ >= 1 && o(2) < rim_z_;
  if (!in_lower_nappe) return false;
  if (n == 0) return true;
  // Ray 0 first: inside the rim usually means a block to solve, answered without the pass over all rays. In
  // single precision the margin is 1e-5 (relative rounding of about 1e-7 per operation).
  const double lim = rim2_ * (sizeof(T) == sizeof(double) ? 1 + 1e-6 : 1 + 1e-5);
  const T o0 = static_cast<T>(o(0)), o1 = static_cast<T>(o(1)), dz = static_cast<T>(rim_z_ - o(2));
  return CountRimCrossings<T>(o0, o1, dz, static_cast<T>(lim), 1, vx, vy, vz) == 0 &&
         CountRimCrossings<T>(o0, o1, dz, static_cast<T>(lim), n, vx, vy, vz) == 0;
}

bool MirrorReflector::MissesRim(const Vec3d& o, int n, const double* vx, const double* vy, const double* vz) const {
  return MissesRimOf(o, n, vx, vy, vz);
}

template <class T>
int MirrorReflector::ReflectBatchOf(const Vec3d& o, int n, const T* vx, const T* vy, const T* vz, T* Mx, T* My, T* Mz,
                                    T* dx, T* dy, T* dz, unsigned char* ok) const {
  // In blocks, with the lane flags as T (a byte array among doubles stops GCC 12's vectoriser).
  constexpr int kBlock = 64;
  T flag[kBlock];
  int hits = 0;
  const double oz = o(2) + c_, C = oz * oz * ia2_ - (o(0) * o(0) + o(1) * o(1)) * ib2_ - 1.0;
  for (int i0 = 0; i0 < n; i0 += kBlock) {
    const int m = std::min(kBlock, n - i0);
    if (MissesRimOf(o, m, vx + i0, vy + i0, vz + i0)) {
      ZeroLanes<T>(m, T(0), Mx + i0, My + i0, Mz + i0, dx + i0, dy + i0, dz + i0, ok + i0);
      continue;
    }
    ReflectKernel<T>(static_cast<T>(c_), static_cast<T>(ia2_), static_cast<T>(ib2_), static_cast<T>(rim2_),
                     static_cast<T>(o(0)), static_cast<T>(o(1)), static_cast<T>(o(2)), static_cast<T>(oz),
                     static_cast<T>(C), m, vx + i0, vy + i0, vz + i0, Mx + i0, My + i0, Mz + i0, dx + i0, dy + i0,
                     dz + i0, flag);
    if (StoreLaneFlags<T>(m, flag, ok + i0, &hits) < 2) continue;
    for (int i = i0; i < i0 + m; ++i) {  // degenerate lanes (flag 2): the scalar solve, in double
      if (ok[i] != 2) continue;
      Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
      ok[i] = Reflect(o, Vec3d(vx[i], vy[i], vz[i]), &M, &d) ? 1 : 0;
      hits += ok[i];
      Mx[i] = static_cast<T>(M(0)), My[i] = static_cast<T>(M(1)), Mz[i] = static_cast<T>(M(2));
      dx[i] = static_cast<T>(d(0)), dy[i] = static_cast<T>(d(1)), dz[i] = static_cast<T>(d(2));
    }
  }
  return hits;
}

int MirrorReflector::ReflectBatch(const Vec3d& o, int n, const double* vx, const double* vy, const double* vz,
                                  double* Mx, double* My, double* Mz, double* dx, double* dy, double* dz,
                                  unsigned char* ok) const {
  return ReflectBatchOf(o, n, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ok);
}

int MirrorReflector::ReflectBatch(const Vec3d& o, int n, const float* vx, const float* vy, const float* vz, float* Mx,
                                  float* My, float* Mz, float* dx, float* dy, float* dz, unsigned char* ok) const {
  return ReflectBatchOf(o, n, vx, vy, vz, Mx, My, Mz, dx, dy, dz, ok);
}

int MirrorReflector::ReflectRays(int n, const double* ox, const double* oy, const double* oz, const double* vx,
                                 const double* vy, const double* vz, double* Mx, double* My, double* Mz, double* dx,
                                 double* dy, double* dz, unsigned char* ok) const {
  constexpr int kBlock = 64;
  double flag[kBlock];
  int hits = 0;
  for (int i0 = 0; i0 < n; i0 += kBlock) {
    const int m = std::min(kBlock, n - i0);
    ReflectRaysKernel(c_, ia2_, ib2_, rim2_, m, ox + i0, oy + i0, oz + i0, vx + i0, vy + i0, vz + i0, Mx + i0, My + i0,
                      Mz + i0, dx + i0, dy + i0, dz + i0, flag);
    if (StoreLaneFlags<double>(m, flag, ok + i0, &hits) < 2) continue;
    for (int i = i0; i < i0 + m; ++i) {  // degenerate lanes (flag 2): the scalar solve
      if (ok[i] != 2) continue;
      Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
      ok[i] = Reflect(Vec3d(ox[i], oy[i], oz[i]), Vec3d(vx[i], vy[i], vz[i]), &M, &d) ? 1 : 0;
      hits += ok[i];
      Mx[i] = M(0), My[i] = M(1), Mz[i] = M(2);
      dx[i] = d(0), dy[i] = d(1), dz[i] = d(2);
    }
  }
  return hits;
}

}  // namespace hovs
