// The hyperboloid mirror (one sheet of a hyperboloid of two sheets), in the mirror frame of conventions.h.
//
//   (z + c)^2 / a^2 - (x^2 + y^2) / b^2 = 1,   c = sqrt(a^2 + b^2)
//   sheet used: z(r) = -c + a * sqrt(1 + r^2 / b^2),  0 <= r <= d / 2   (d: rim diameter)
//
// Foci: F1 = (0, 0, 0), the single effective viewpoint, inside the sheet; F2 = (0, 0, -2c), where the camera
// pinhole belongs. A ray aimed at F1 that meets the sheet reflects towards F2. The reflective side faces the
// camera; Normal() returns the unit normal on that side (pointing away from F1, roughly towards -z).
//
// Parameters, in order: a, b, rim diameter d (metres). Valid: a > 0, b > 0, d > 0, all finite.
#pragma once

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/types.h"

namespace hovs {

template <class T>
struct HyperboloidMirror {
  T a = T(0), b = T(0), rim_diameter = T(0);

  T c() const {
    using std::sqrt;
    return sqrt(a * a + b * b);
  }
  T RimRadius() const { return rim_diameter * T(0.5); }
  // Second focus, where the ideal camera pinhole sits.
  Vec3<T> SecondFocus() const { return Vec3<T>(T(0), T(0), T(-2) * c()); }

  // Sheet height z at radius r.
  T SheetZ(const T& r) const {
    using std::sqrt;
    return -c() + a * sqrt(T(1) + r * r / (b * b));
  }
  T RimZ() const { return SheetZ(RimRadius()); }
  // Vertex of the sheet (r = 0): z = a - c.
  T VertexZ() const { return a - c(); }

  // The sheet point above (x, y); differentiable at the vertex.
  Vec3<T> SurfacePoint(const T& x, const T& y) const {
    using std::sqrt;
    return Vec3<T>(x, y, -c() + a * sqrt(T(1) + (x * x + y * y) / (b * b)));
  }

  // Partial derivatives dz/dx, dz/dy of the sheet at (x, y).
  Vec2<T> Slope(const T& x, const T& y) const {
    using std::sqrt;
    const T s = sqrt(T(1) + (x * x + y * y) / (b * b));
    const T k = a / (b * b * s);
    return Vec2<T>(k * x, k * y);
  }

  // Unit normal on the reflective side at a point p of the sheet.
  Vec3<T> Normal(const Vec3<T>& p) const {
    const T ib2 = T(1) / (b * b);
    const Vec3<T> n(p(0) * ib2, p(1) * ib2, -(p(2) + c()) / (a * a));
    return Normalized(n);
  }

  bool WithinRim(const Vec3<T>& p) const {
    const double r2 = ScalarPart(p(0)) * ScalarPart(p(0)) + ScalarPart(p(1)) * ScalarPart(p(1));
    const double rr = ScalarPart(RimRadius());
    return r2 <= rr * rr * (1 + 1e-12);
  }

  // The mirror point seen from F1 in direction s (any length): M = lambda * s / |s| with
  // lambda = b^2 / (a - c * s_z / |s|). False when the direction misses the sheet (s_z / |s| >= a / c).
  bool PointAlong(const Vec3<T>& s, Vec3<T>* m) const {
    using std::sqrt;
    const T n = sqrt(s.squaredNorm());
    if (!(ScalarPart(n) > 0)) return false;
    const T denom = a - c() * s(2) / n;
    if (!(ScalarPart(denom) > 0)) return false;
    *m = (b * b / denom) * (s / n);
    return true;
  }

  // Intersection of the ray o + t v (t > t_min) with the sheet: the smallest such t on the upper sheet
  // (z + c > 0). Does not test the rim. Solves the quadratic in a cancellation-free form.
  bool IntersectSheet(const Vec3<T>& o, const Vec3<T>& v, T* t, double t_min = 0.0) const {
    return IntersectSheetWith(c(), T(1) / (a * a), T(1) / (b * b), o, v, t, t_min);
  }

  // IntersectSheet with the mirror's constants given (c, 1 / a^2, 1 / b^2): shared with MirrorReflector,
  // which computes them once for many rays.
  static bool IntersectSheetWith(const T& cc, const T& ia2, const T& ib2, const Vec3<T>& o, const Vec3<T>& v, T* t,
                                 double t_min = 0.0) {
    using std::abs;
    using std::sqrt;
    const T oz = o(2) + cc;
    const T A = v(2) * v(2) * ia2 - (v(0) * v(0) + v(1) * v(1)) * ib2;
    const T B = oz * v(2) * ia2 - (o(0) * v(0) + o(1) * v(1)) * ib2;
    const T C = oz * oz * ia2 - (o(0) * o(0) + o(1) * o(1)) * ib2 - T(1);
    T roots[2];
    int count = 0;
    const double scale = std::abs(ScalarPart(B)) + std::abs(ScalarPart(A)) + 1e-300;
    if (std::abs(ScalarPart(A)) < 1e-14 * scale) {
      if (ScalarPart(B) == 0) return false;
      roots[count++] = -C / (T(2) * B);
    } else {
      const T disc = B * B - A * C;
      if (ScalarPart(disc) < 0) return false;
      const T sq = sqrt(disc);
      const T q = ScalarPart(B) >= 0 ? -(B + sq) : -(B - sq);
      if (ScalarPart(q) != 0) {
        // C / q and q / A from one division (ReflectBatch's per-ray cost is the divider's).
        const T inv = T(1) / (q * A);
        roots[count++] = C * A * inv;
        roots[count++] = q * q * inv;
      } else {
        roots[count++] = q / A;
      }
    }
    bool found = false;
    for (int i = 0; i < count; ++i) {
      const double ti = ScalarPart(roots[i]);
      if (!(ti > t_min) || !std::isfinite(ti)) continue;
      if (!(ScalarPart(o(2) + roots[i] * v(2) + cc) > 0)) continue;  // lower sheet
      if (!found || ti < ScalarPart(*t)) {
        *t = roots[i];
        found = true;
      }
    }
    return found;
  }

  void Check(const std::string& where = "mirror") const {
    const double va = ScalarPart(a), vb = ScalarPart(b), vd = ScalarPart(rim_diameter);
    HOVS_REQUIRE(std::isfinite(va) && std::isfinite(vb) && std::isfinite(vd), where,
                 "a, b and the rim diameter must be finite numbers");
    HOVS_REQUIRE(va > 0 && va <= 10, where, "a must be in (0, 10] m (got ", va, ")");
    HOVS_REQUIRE(vb > 0 && vb <= 10, where, "b must be in (0, 10] m (got ", vb, ")");
    HOVS_REQUIRE(vd > 0 && vd <= 10, where, "the rim diameter must be in (0, 10] m (got ", vd, ")");
  }

  template <class U>
  HyperboloidMirror<U> Cast() const {
    return {ConvertScalar<U>(a), ConvertScalar<U>(b), ConvertScalar<U>(rim_diameter)};
  }
};

// The renderer's hot path: the reflection of many camera rays by one mirror in double precision, with the
// mirror's constants (c, 1/a^2, 1/b^2, rim radius^2) computed once and the normal left unnormalised. The
// intersection is HyperboloidMirror::IntersectSheetWith itself; the rim test and the law of reflection are
// those of WithinRim / Normal; tests assert agreement with ReflectCameraRay to 1e-12.
class MirrorReflector {
 public:
  explicit MirrorReflector(const HyperboloidMirror<double>& m)
      : c_(m.c()),
        ia2_(1.0 / (m.a * m.a)),
        ib2_(1.0 / (m.b * m.b)),
        rim2_(m.RimRadius() * m.RimRadius() * (1 + 1e-12)),
        rim_z_(m.RimZ()) {}

  // Ray o + t v (mirror frame, v any length): the mirror point within the rim and the unit reflected direction.
  bool Reflect(const Vec3d& o, const Vec3d& v, Vec3d* mirror_point, Vec3d* direction) const {
    double t = 0;
    if (!HyperboloidMirror<double>::IntersectSheetWith(c_, ia2_, ib2_, o, v, &t)) return false;
    const double M0 = o(0) + t * v(0), M1 = o(1) + t * v(1), M2 = o(2) + t * v(2);
    if (!(M0 * M0 + M1 * M1 <= rim2_)) return false;
    ReflectAt(v(0), v(1), v(2), M0, M1, M2, &(*direction)(0), &(*direction)(1), &(*direction)(2));
    *mirror_point = Vec3d(M0, M1, M2);
    return true;
  }

  // Reflect for n rays from one origin o with directions in structure-of-arrays form (any length), written so
  // the compiler vectorises it (AVX2 where the CPU has it, chosen at load time). The results are bit-identical
  // to Reflect's, on every CPU (the same operations in the same order, and no fused multiply-add). ok[i] = 1
  // where ray i meets the mirror within the rim, else 0; M and d are meaningful only where ok[i] = 1. Returns the
  // count of rays that meet it.
  // Blocks of rays that all pass the rim plane outside the rim are answered without solving: see MissesRim.
  int ReflectBatch(const Vec3d& o, int n, const double* vx, const double* vy, const double* vz, double* Mx, double* My,
                   double* Mz, double* dx, double* dy, double* dz, unsigned char* ok) const;
  // The same in single precision (twice the lanes per vector): the renderer's colour samples. The same operations
  // in float (the mirror's constants and the origin's terms rounded from double), so M and d carry single
  // precision's relative rounding, about 1e-7 (tests bound them against Reflect); the rim test is made on the
  // float M. Lanes whose quadratic degenerates in float are solved by Reflect in double.
  int ReflectBatch(const Vec3d& o, int n, const float* vx, const float* vy, const float* vz, float* Mx, float* My,
                   float* Mz, float* dx, float* dy, float* dz, unsigned char* ok) const;

  // ReflectBatch (double) with an origin per ray, (ox[i], oy[i], oz[i]): thin-lens samples, which leave points of
  // the aperture. Bit-identical to Reflect on each ray; no block is skipped (MissesRim needs one origin).
  int ReflectRays(int n, const double* ox, const double* oy, const double* oz, const double* vx, const double* vy,
                  const double* vz, double* Mx, double* My, double* Mz, double* dx, double* dy, double* dz,
                  unsigned char* ok) const;

  // True when every ray o + t v (v any length) of the n given provably misses the mirror within the rim: o lies
  // inside the lower nappe (where the camera of any rig sits, at or near the second focus) and each ray goes down
  // or passes the rim plane z = RimZ at least 1e-4 % outside the rim. Why that suffices: from inside the lower
  // nappe every direction towards the upper sheet lies strictly inside its asymptotic cone (the sum of two vectors
  // of that convex cone), so such a ray, once inside the upper nappe, never leaves it; the solid under the rim
  // plane inside the upper nappe is convex, its boundary the mirror within the rim and the rim disc; a ray
  // crossing the rim plane outside the disc is outside that solid there, so it never entered it from below, so it
  // never met the mirror within the rim. Exact in real numbers; the margin covers rounding and rim2_'s 1e-12.
  bool MissesRim(const Vec3d& o, int n, const double* vx, const double* vy, const double* vz) const;

  // The law of reflection at mirror point M for incoming direction v (unnormalised normal of Normal()).
  void ReflectAt(double v0, double v1, double v2, double M0, double M1, double M2, double* d0, double* d1,
                 double* d2) const {
    const double n0 = M0 * ib2_, n1 = M1 * ib2_, n2 = -(M2 + c_) * ia2_;
    // r = v - 2 (v.n) / (n.n) n has the length of v (a reflection); 1 / (n.n) and 1 / |v| come from one division.
    const double nn = n0 * n0 + n1 * n1 + n2 * n2, vlen = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
    const double g = 1.0 / (nn * vlen);
    const double k = 2 * (v0 * n0 + v1 * n1 + v2 * n2) * (g * vlen);
    const double r0 = v0 - k * n0, r1 = v1 - k * n1, r2 = v2 - k * n2;
    const double inv_len = g * nn;
    *d0 = r0 * inv_len, *d1 = r1 * inv_len, *d2 = r2 * inv_len;
  }

 private:
  template <class T>
  bool MissesRimOf(const Vec3d& o, int n, const T* vx, const T* vy, const T* vz) const;
  template <class T>
  int ReflectBatchOf(const Vec3d& o, int n, const T* vx, const T* vy, const T* vz, T* Mx, T* My, T* Mz, T* dx, T* dy,
                     T* dz, unsigned char* ok) const;
  double c_, ia2_, ib2_, rim2_, rim_z_;
};

}  // namespace hovs
