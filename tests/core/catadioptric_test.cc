// The exact hyperboloid model: sheet geometry, single-viewpoint property, closed-form and general projection,
// back-projection round trips, the law of reflection, the mirror mask.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/catadioptric.h"
#include "core/sincos.h"
#include "tests/core/test_rigs.h"

namespace hovs {
namespace {

constexpr double kDeg = M_PI / 180;

double AngleBetween(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

TEST(Hyperboloid, SheetSatisfiesImplicitEquationAndNormalIsPerpendicular) {
  const auto m = test::ReferenceMirror();
  for (double r = 0; r <= m.RimRadius(); r += 0.004) {
    const Vec3d p = m.SurfacePoint(r * 0.6, r * 0.8);
    const double g = std::pow(p.z() + m.c(), 2) / (m.a * m.a) - (p.x() * p.x() + p.y() * p.y()) / (m.b * m.b);
    EXPECT_NEAR(g, 1.0, 1e-14);
    const double h = 1e-7;
    const Vec3d tx = (m.SurfacePoint(p.x() + h, p.y()) - m.SurfacePoint(p.x() - h, p.y())) / (2 * h);
    const Vec3d ty = (m.SurfacePoint(p.x(), p.y() + h) - m.SurfacePoint(p.x(), p.y() - h)) / (2 * h);
    const Vec3d n = m.Normal(p);
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    EXPECT_NEAR(n.dot(tx.normalized()), 0.0, 1e-8);
    EXPECT_NEAR(n.dot(ty.normalized()), 0.0, 1e-8);
    EXPECT_LT(n.z(), 0.0) << "the reflective side faces the camera";
  }
  EXPECT_NEAR(m.VertexZ(), m.SheetZ(0.0), 1e-15);
}

TEST(Hyperboloid, RaysAimedAtTheViewpointReflectThroughTheSecondFocus) {
  const auto m = test::ReferenceMirror();
  for (double el = -80; el <= 40; el += 5) {
    for (double az = 0; az < 360; az += 45) {
      const Vec3d s(std::cos(el * kDeg) * std::cos(az * kDeg), std::cos(el * kDeg) * std::sin(az * kDeg),
                    std::sin(el * kDeg));
      Vec3d M = Vec3d::Zero();
      if (!m.PointAlong(s, &M)) {
        EXPECT_GE(s.z(), m.a / m.c() - 1e-12);
        continue;
      }
      const Vec3d incident = -s;  // travelling from the world towards F1
      const Vec3d n = m.Normal(M);
      const Vec3d reflected = incident - 2 * incident.dot(n) * n;
      EXPECT_LT(AngleBetween(reflected, m.SecondFocus() - M), 1e-12);
      // The sheet intersection from F1 agrees with the closed form.
      double t = 0;
      ASSERT_TRUE(m.IntersectSheet(Vec3d::Zero(), s, &t));
      EXPECT_NEAR((t * s - M).norm(), 0.0, 1e-15);
    }
  }
}

TEST(Hyperboloid, IntersectionFromTheCameraHitsTheSheet) {
  const auto m = test::ReferenceMirror();
  const Vec3d C = m.SecondFocus();
  for (double ang = 0; ang < 20; ang += 0.5) {
    const Vec3d v(std::sin(ang * kDeg), 0.3 * std::sin(ang * kDeg), std::cos(ang * kDeg));
    double t = 0;
    ASSERT_TRUE(m.IntersectSheet(C, v.normalized(), &t));
    const Vec3d p = C + t * v.normalized();
    EXPECT_NEAR(p.z(), m.SheetZ(std::hypot(p.x(), p.y())), 1e-15);
  }
  double t = 0;
  EXPECT_FALSE(m.IntersectSheet(C, Vec3d(0, 0, -1), &t)) << "pointing away from the mirror";
}

TEST(Catadioptric, AlignedRoundTripPixelRayPixel) {
  const auto rig = test::AlignedRig();
  ASSERT_TRUE(rig.IsSingleViewpoint());
  const auto pixels = test::MirrorPixels(rig, 37);
  ASSERT_GT(pixels.size(), 2000u);
  double worst = 0;
  for (const Vec2d& uv : pixels) {
    Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
    ASSERT_TRUE(rig.RayFromImg(uv, &M, &d));
    EXPECT_NEAR(d.norm(), 1.0, 1e-14);
    EXPECT_LT(AngleBetween(d, M), 1e-12) << "single viewpoint: the view ray passes through F1";
    for (double range : {0.3, 3.0, 300.0}) {
      Vec2d back = Vec2d::Zero();
      ASSERT_EQ(rig.ImgFromMirror(M + range * d, &back), ProjectionStatus::kOk) << uv.transpose();
      worst = std::max(worst, (back - uv).norm());
    }
  }
  EXPECT_LT(worst, 1e-9);
  RecordProperty("worst_round_trip_px", std::to_string(worst));
}

TEST(Catadioptric, MisalignedRoundTripThroughTheGeneralProjection) {
  const auto rig = test::MisalignedRig();
  ASSERT_FALSE(rig.IsSingleViewpoint());
  const auto pixels = test::MirrorPixels(rig, 53);
  ASSERT_GT(pixels.size(), 1000u);
  double worst = 0;
  for (const Vec2d& uv : pixels) {
    Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
    ASSERT_TRUE(rig.RayFromImg(uv, &M, &d));
    for (double range : {0.5, 20.0}) {
      Vec2d back = Vec2d::Zero();
      ASSERT_EQ(rig.ImgFromMirror(M + range * d, &back), ProjectionStatus::kOk) << uv.transpose();
      worst = std::max(worst, (back - uv).norm());
    }
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Catadioptric, FastReflectorAgreesWithTheTemplatedReflection) {
  // MirrorReflector (the renderer's path) against ReflectCameraRay for every pixel's ray of an aligned and a
  // misaligned rig, plus rays that miss (outside the rim, pointing away): same decision, same point and
  // direction to 1e-12.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 1);
  for (const auto& rig : {test::AlignedRig(), test::MisalignedRig()}) {
    const MirrorReflector fast(rig.mirror);
    const Vec3d C = rig.CameraCentre();
    int hits = 0, misses = 0;
    double worst = 0;
    for (int k = 0; k < 20000; ++k) {
      // Directions from the camera centre spread well beyond the mirror (some miss the rim), and some origins
      // moved about the centre like a thin lens's aperture.
      const Vec3d o = C + (k % 3 == 0 ? Vec3d(0.004 * U(rng), 0.004 * U(rng), 0.0) : Vec3d::Zero());
      const Vec3d v(0.4 * U(rng), 0.4 * U(rng), k % 50 == 0 ? -1.0 : 1.0);
      Vec3d M1 = Vec3d::Zero(), d1 = Vec3d::Zero(), M2 = Vec3d::Zero(), d2 = Vec3d::Zero();
      const bool a = rig.ReflectCameraRay(o, v, &M1, &d1), b = fast.Reflect(o, v, &M2, &d2);
      ASSERT_EQ(a, b) << "ray " << k;
      if (!a) {
        ++misses;
        continue;
      }
      ++hits;
      worst = std::max({worst, (M1 - M2).norm(), (d1 - d2).norm()});
    }
    EXPECT_GT(hits, 5000);
    EXPECT_GT(misses, 1000);
    EXPECT_LT(worst, 1e-12);
  }
}

// Rays from a rig's camera centre for the batch reflection tests (not unit length): every 97th parallel to the
// asymptotic cone (A = 0, the degenerate quadratic); rays 1-127 27-45 degrees off the axis (past the rim, which is
// about 17 degrees off it from the camera); the rest within 22 degrees of it, every 50th pointing away.
std::vector<Vec3d> BatchTestRays(const CatadioptricCamera<double>& rig, int n, std::mt19937* rng) {
  std::uniform_real_distribution<double> U(-1, 1);
  const double a = rig.mirror.a, b = rig.mirror.b;
  std::vector<Vec3d> v(n);
  for (int i = 0; i < n; ++i) {
    if (i % 97 == 0) {
      const double phi = U(*rng) * M_PI;
      v[i] = Vec3d(b * std::cos(phi), b * std::sin(phi), a);
    } else if (i < 128) {
      const double phi = U(*rng) * M_PI, r = 0.75 + 0.25 * U(*rng);
      v[i] = Vec3d(r * std::cos(phi), r * std::sin(phi), 1.0);
    } else {
      v[i] = Vec3d(0.4 * U(*rng), 0.4 * U(*rng), i % 50 == 1 ? -1.0 : 1.0);
    }
  }
  return v;
}

// A double-precision batch reflection's outputs, by ray.
struct BatchOutputs {
  const std::vector<double>&Mx, &My, &Mz, &dx, &dy, &dz;
  const std::vector<unsigned char>& ok;
};

// Every ray of a batch reflection (origins[i], direction (vx, vy, vz)[i]) against Reflect, exactly: the same
// decision and every bit of M and d; count, the batch's returned count of hits. Over 300 hits and 100 misses.
void ExpectTheScalarReflections(const MirrorReflector& fast, const std::vector<Vec3d>& origins,
                                const std::vector<double>& vx, const std::vector<double>& vy,
                                const std::vector<double>& vz, const BatchOutputs& out, int count) {
  int hits = 0, misses = 0;
  for (size_t i = 0; i < origins.size(); ++i) {
    Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
    const bool hit = fast.Reflect(origins[i], Vec3d(vx[i], vy[i], vz[i]), &M, &d);
    ASSERT_EQ(out.ok[i], hit ? 1 : 0) << "ray " << i;
    if (!hit) {
      ++misses;
      continue;
    }
    ++hits;
    EXPECT_EQ(out.Mx[i], M(0)) << i;
    EXPECT_EQ(out.My[i], M(1)) << i;
    EXPECT_EQ(out.Mz[i], M(2)) << i;
    EXPECT_EQ(out.dx[i], d(0)) << i;
    EXPECT_EQ(out.dy[i], d(1)) << i;
    EXPECT_EQ(out.dz[i], d(2)) << i;
  }
  EXPECT_GT(hits, 300);
  EXPECT_GT(misses, 100);
  EXPECT_EQ(count, hits) << "the batch returns the count of rays that meet the mirror";
}

TEST(Catadioptric, BatchReflectionIsBitIdenticalToTheScalarOne) {
  // ReflectBatch (vectorised; the renderer's per-sample path) against Reflect, exactly: every decision and
  // every bit of M and d. Rays (BatchTestRays): spread past the rim, pointing away, and along the asymptotic cone where
  // the quadratic degenerates (those lanes take the scalar code); 1001 rays, so the vector loop has a remainder. The
  // first two blocks of 64 rays all pass outside the rim, so ReflectBatch answers them without solving.
  std::mt19937 rng(5);
  for (const auto& rig : {test::AlignedRig(), test::MisalignedRig()}) {
    const MirrorReflector fast(rig.mirror);
    const Vec3d o = rig.CameraCentre();
    const int n = 1001;
    std::vector<double> vx(n), vy(n), vz(n), Mx(n), My(n), Mz(n), dx(n), dy(n), dz(n);
    std::vector<unsigned char> ok(n);
    const std::vector<Vec3d> rays = BatchTestRays(rig, n, &rng);
    for (int i = 0; i < n; ++i) vx[i] = rays[i].x(), vy[i] = rays[i].y(), vz[i] = rays[i].z();
    ASSERT_TRUE(fast.MissesRim(o, 64, vx.data(), vy.data(), vz.data()));
    ASSERT_TRUE(fast.MissesRim(o, 64, vx.data() + 64, vy.data() + 64, vz.data() + 64));
    ASSERT_FALSE(fast.MissesRim(o, 64, vx.data() + 128, vy.data() + 128, vz.data() + 128));
    const int count = fast.ReflectBatch(o, n, vx.data(), vy.data(), vz.data(), Mx.data(), My.data(), Mz.data(),
                                        dx.data(), dy.data(), dz.data(), ok.data());
    const std::vector<Vec3d> origins(n, o);
    const BatchOutputs out{Mx, My, Mz, dx, dy, dz, ok};
    ExpectTheScalarReflections(fast, origins, vx, vy, vz, out, count);
  }
}

TEST(SinCos, OfTurnsMatchesTheLibraryToTheLastBitsOverSeveralTurns) {
  // SinCosOfTurns (basic arithmetic only, the thin-lens samples' angle) against std::sin / std::cos of 2 pi w in
  // long double, over [-3, 3] turns, every quarter-turn boundary and its neighbours included.
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-3, 3);
  std::vector<double> ws;
  for (int i = 0; i < 20000; ++i) ws.push_back(U(rng));
  for (int q = -12; q <= 12; ++q)
    for (const double e : {-1e-12, 0.0, 1e-12, 0.125, -0.125}) ws.push_back(q / 4.0 + e);
  double worst = 0;
  for (const double w : ws) {
    double s = 0, c = 0;
    SinCosOfTurns(w, &s, &c);
    const long double a = 2.0L * 3.14159265358979323846264338327950288L * w;
    worst = std::max(
        {worst, std::abs(s - static_cast<double>(std::sin(a))), std::abs(c - static_cast<double>(std::cos(a)))});
  }
  EXPECT_LT(worst, 3e-16);
  double s = 1, c = 0;
  SinCosOfTurns(0.0, &s, &c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  SinCosOfTurns(0.25, &s, &c);
  EXPECT_EQ(s, 1.0);
  EXPECT_EQ(c, 0.0);
  std::printf("[ figure ] SinCosOfTurns: worst error %.2g over %zu angles\n", worst, ws.size());
}

TEST(Catadioptric, BatchReflectionWithAnOriginPerRayIsBitIdenticalToTheScalarOne) {
  // ReflectRays (thin-lens samples: each ray leaves its own point of the aperture) against Reflect, exactly. The
  // origins spread over a 10 mm disc across the camera's axis (a wide aperture) and 1 mm along it; the rays are
  // BatchTestRays' (past the rim, pointing away, degenerate lanes taking the scalar code); 1001 of them, so the
  // vector loop has a remainder.
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> U(-1, 1);
  for (const auto& rig : {test::AlignedRig(), test::MisalignedRig()}) {
    const MirrorReflector fast(rig.mirror);
    const Vec3d c = rig.CameraCentre();
    const int n = 1001;
    std::vector<double> ox(n), oy(n), oz(n), vx(n), vy(n), vz(n), Mx(n), My(n), Mz(n), dx(n), dy(n), dz(n);
    std::vector<unsigned char> ok(n);
    const std::vector<Vec3d> rays = BatchTestRays(rig, n, &rng);
    for (int i = 0; i < n; ++i) {
      ox[i] = c.x() + 0.01 * U(rng), oy[i] = c.y() + 0.01 * U(rng), oz[i] = c.z() + 0.001 * U(rng);
      vx[i] = rays[i].x(), vy[i] = rays[i].y(), vz[i] = rays[i].z();
    }
    const int count = fast.ReflectRays(n, ox.data(), oy.data(), oz.data(), vx.data(), vy.data(), vz.data(), Mx.data(),
                                       My.data(), Mz.data(), dx.data(), dy.data(), dz.data(), ok.data());
    std::vector<Vec3d> origins(n);
    for (int i = 0; i < n; ++i) origins[i] = Vec3d(ox[i], oy[i], oz[i]);
    const BatchOutputs out{Mx, My, Mz, dx, dy, dz, ok};
    ExpectTheScalarReflections(fast, origins, vx, vy, vz, out, count);
  }
}

TEST(Catadioptric, SinglePrecisionBatchReflectionIsWithinFloatRoundingOfTheScalarOne) {
  // The float ReflectBatch (the renderer's colour samples) against Reflect in double on the same (float) rays:
  // the same decision except for rays within 1e-5 of the rim; M within 1e-7 m (float's spacing at the camera,
  // 0.13 m from F1, is 1.5e-8 m) and d within 1e-6 rad (a few thousandths of a pixel of the reference rig).
  // Rays as above (BatchTestRays, made unit), degenerate lanes included.
  std::mt19937 rng(6);
  for (const auto& rig : {test::AlignedRig(), test::MisalignedRig()}) {
    const MirrorReflector fast(rig.mirror);
    const Vec3d o = rig.CameraCentre();
    const int n = 1001;
    std::vector<float> vx(n), vy(n), vz(n), Mx(n), My(n), Mz(n), dx(n), dy(n), dz(n);
    std::vector<unsigned char> ok(n);
    const std::vector<Vec3d> rays = BatchTestRays(rig, n, &rng);
    for (int i = 0; i < n; ++i) {
      const Vec3d v = rays[i].normalized();
      vx[i] = static_cast<float>(v.x()), vy[i] = static_cast<float>(v.y()), vz[i] = static_cast<float>(v.z());
    }
    const int count = fast.ReflectBatch(o, n, vx.data(), vy.data(), vz.data(), Mx.data(), My.data(), Mz.data(),
                                        dx.data(), dy.data(), dz.data(), ok.data());
    EXPECT_EQ(count, std::count(ok.begin(), ok.end(), 1));
    int hits = 0, misses = 0;
    double worst_M = 0, worst_d = 0;
    for (int i = 0; i < n; ++i) {
      Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
      const bool hit = fast.Reflect(o, Vec3d(vx[i], vy[i], vz[i]), &M, &d);
      const double rim = hit ? std::hypot(M.x(), M.y()) / rig.mirror.RimRadius() : 0.0;
      if (hit && rim > 1 - 1e-5) continue;  // at the rim: either answer
      ASSERT_EQ(ok[i], hit ? 1 : 0) << "ray " << i;
      if (!hit) {
        ++misses;
        continue;
      }
      ++hits;
      worst_M = std::max(worst_M, (Vec3d(Mx[i], My[i], Mz[i]) - M).norm());
      worst_d = std::max(worst_d, (Vec3d(dx[i], dy[i], dz[i]) - d).norm());
    }
    EXPECT_GT(hits, 300);
    EXPECT_GT(misses, 100);
    EXPECT_LT(worst_M, 1e-7);
    EXPECT_LT(worst_d, 1e-6);
    std::printf("[ figure ] float ReflectBatch vs Reflect: M within %.2g m, d within %.2g rad\n", worst_M, worst_d);
    EXPECT_GT(worst_d, 0.0) << "single precision, not the double path";
  }
}

TEST(Catadioptric, RaysSkippedByTheRimPlaneTestNeverMeetTheMirror) {
  // MissesRim lets ReflectBatch skip blocks of rays without solving; it must never skip a ray that Reflect says
  // meets the mirror. Rays from the camera centres of the aligned and misaligned rigs and of a camera 5 mm off the
  // focus, aimed at the rim plane at radii from 0.9 to 1.1 rim radii (and a band within 1e-5 of the rim itself);
  // every ray that crosses within the rim must meet the mirror, and MissesRim must say so for every one outside
  // by more than its margin.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(0, 1);
  auto shifted = test::AlignedRig();
  shifted.cam_from_mirror.translation += Vec3d(0.005, -0.003, 0.004);
  for (const auto& rig : {test::AlignedRig(), test::MisalignedRig(), shifted}) {
    const MirrorReflector fast(rig.mirror);
    const Vec3d o = rig.CameraCentre();
    const double r0 = rig.mirror.RimRadius(), zr = rig.mirror.RimZ();
    int inside = 0, outside = 0, skipped = 0;
    for (int i = 0; i < 20000; ++i) {
      const double phi = 2 * M_PI * U(rng);
      const double rel = i % 2 == 0 ? 0.9 + 0.2 * U(rng) : 1.0 + 1e-5 * (2 * U(rng) - 1);
      const Vec3d target(rel * r0 * std::cos(phi), rel * r0 * std::sin(phi), zr);
      const Vec3d v = (target - o) * (0.5 + U(rng));  // any length
      Vec3d M, d;
      const bool hit = fast.Reflect(o, v, &M, &d);
      const bool skip = fast.MissesRim(o, 1, &v.x(), &v.y(), &v.z());
      if (skip) {
        ++skipped;
        ASSERT_FALSE(hit) << "ray " << i << " at " << rel << " rim radii was skipped but meets the mirror";
      }
      if (rel < 1 - 1e-9) {
        ++inside;
        ASSERT_TRUE(hit) << "ray " << i << " crosses the rim plane at " << rel << " rim radii";
      } else if (rel > 1 + 1e-6) {
        ++outside;
        ASSERT_TRUE(skip) << "ray " << i << " at " << rel << " rim radii";
      }
    }
    EXPECT_GT(inside, 9000);
    EXPECT_GT(outside, 4000);
    EXPECT_GE(skipped, outside);
    // A ray pointing down never meets the mirror; an origin outside the lower nappe is never skipped.
    const Vec3d down(0.01, 0.0, -1.0), up(0.9, 0.0, 1.0);
    EXPECT_TRUE(fast.MissesRim(o, 1, &down.x(), &down.y(), &down.z()));
    const Vec3d beside(0.3, 0.0, zr - 0.01);
    EXPECT_FALSE(fast.MissesRim(beside, 1, &up.x(), &up.y(), &up.z()));
  }
}

TEST(Catadioptric, LawOfReflectionHoldsAtTheSolvedMirrorPoint) {
  const auto rig = test::MisalignedRig();
  const Vec3d C = rig.CameraCentre();
  int solved = 0;
  for (const Vec3d& X : test::WorldPoints(400, 7)) {
    Vec3d M = Vec3d::Zero();
    if (rig.SolveReflectionPoint(X, &M) != ProjectionStatus::kOk) continue;
    ++solved;
    const Vec3d n = rig.mirror.Normal(M);
    const Vec3d to_world = (X - M).normalized(), to_camera = (C - M).normalized();
    // Incidence equals reflection, and the reflected ray passes through the camera pinhole.
    EXPECT_LT(std::abs(AngleBetween(to_world, n) - AngleBetween(to_camera, n)), 1e-9);
    const Vec3d incident = -to_world;
    const Vec3d reflected = incident - 2 * incident.dot(n) * n;
    EXPECT_LT(AngleBetween(reflected, to_camera), 1e-9);
    EXPECT_LT((C - M).cross(reflected).norm(), 1e-12) << "distance of the pinhole from the reflected ray";
    EXPECT_NEAR(M.z(), rig.mirror.SheetZ(std::hypot(M.x(), M.y())), 1e-15);
  }
  EXPECT_GT(solved, 350);
}

TEST(Catadioptric, GeneralProjectionEqualsClosedFormWhenAligned) {
  const auto rig = test::AlignedRig();
  int compared = 0;
  for (const Vec3d& X : test::WorldPoints(500, 11)) {
    Vec2d a = Vec2d::Zero(), b = Vec2d::Zero();
    const auto sa = rig.ImgFromMirrorSvp(X, &a);
    const auto sb = rig.ImgFromMirrorGeneral(X, &b);
    ASSERT_EQ(sa, sb) << X.transpose();
    if (sa != ProjectionStatus::kOk) continue;
    ++compared;
    EXPECT_LT((a - b).norm(), 1e-9);
  }
  EXPECT_GT(compared, 400);
}

TEST(Catadioptric, LensDistortionIsPartOfTheExactModel) {
  auto rig = test::AlignedRig();
  rig.camera.distortion = {-0.08, 0.02, 1e-4, -2e-4};
  double worst = 0;
  for (const Vec2d& uv : test::MirrorPixels(rig, 61)) {
    Vec3d M = Vec3d::Zero(), d = Vec3d::Zero();
    ASSERT_TRUE(rig.RayFromImg(uv, &M, &d));
    Vec2d back = Vec2d::Zero();
    ASSERT_EQ(rig.ImgFromMirror(M + 2.0 * d, &back), ProjectionStatus::kOk);
    worst = std::max(worst, (back - uv).norm());
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Catadioptric, MaskSeparatesMirrorRimAndCameraReflection) {
  const auto rig = test::AlignedRig();
  const double cx = rig.camera.cx, cy = rig.camera.cy;
  const auto [rho_min, rho_max] = std::pair<double, double>(
      [&] {
        Vec3d M = Vec3d::Zero();
        rig.mirror.PointAlong(Vec3d(rig.occluder_radius, 0, -2 * rig.mirror.c()), &M);
        Vec2d uv = Vec2d::Zero();
        rig.camera.ImgFromCam(rig.cam_from_mirror * M, &uv);
        return uv.x() - cx;
      }(),
      [&] {
        Vec2d uv = Vec2d::Zero();
        rig.camera.ImgFromCam(rig.cam_from_mirror * Vec3d(rig.mirror.RimRadius(), 0, rig.mirror.RimZ()), &uv);
        return uv.x() - cx;
      }());
  EXPECT_FALSE(rig.SeesMirror(Vec2d(cx, cy))) << "the centre shows the camera";
  EXPECT_FALSE(rig.SeesMirror(Vec2d(cx + rho_min - 0.01, cy)));
  EXPECT_TRUE(rig.SeesMirror(Vec2d(cx + rho_min + 0.01, cy)));
  EXPECT_TRUE(rig.SeesMirror(Vec2d(cx + rho_max - 0.01, cy)));
  EXPECT_FALSE(rig.SeesMirror(Vec2d(cx + rho_max + 0.01, cy)));
  EXPECT_FALSE(rig.SeesMirror(Vec2d(0, 0))) << "image corner, outside the rim";
  EXPECT_FALSE(rig.SeesMirror(Vec2d(-5, cy))) << "outside the image";
  // The article's sheet: the rim at about 1084 px.
  EXPECT_NEAR(rho_max, 1084.0, 1.0);
}

TEST(Catadioptric, ProjectionReportsWhyAPointIsNotSeen) {
  const auto aligned = test::AlignedRig();
  Vec2d uv = Vec2d::Zero();
  EXPECT_EQ(aligned.ImgFromMirror(Vec3d(0.1, 0, 5.0), &uv), ProjectionStatus::kMissesMirror) << "above";
  EXPECT_EQ(aligned.ImgFromMirror(Vec3d(0.0, 0.001, -3.0), &uv), ProjectionStatus::kOccluded) << "below";
  EXPECT_EQ(aligned.ImgFromMirror(Vec3d(0.001, 0.0, -0.005), &uv), ProjectionStatus::kInsideMirror);
  // The numeric solve says so too, with a failure status rather than a pixel.
  const auto misaligned = test::MisalignedRig();
  EXPECT_NE(misaligned.ImgFromMirror(Vec3d(0.1, 0, 5.0), &uv), ProjectionStatus::kOk);
  EXPECT_EQ(misaligned.ImgFromMirror(Vec3d(0.0, 0.001, -3.0), &uv), ProjectionStatus::kOccluded);
  EXPECT_NE(misaligned.ImgFromMirror(Vec3d(0.001, 0.0, -0.005), &uv), ProjectionStatus::kOk);
}

TEST(Catadioptric, CheckRejectsImpossibleRigs) {
  auto rig = test::AlignedRig();
  EXPECT_NO_THROW(rig.Check());
  auto bad = rig;
  bad.mirror.a = -0.01;
  EXPECT_THROW(bad.Check(), Error);
  bad = rig;
  bad.camera.fx = 0;
  EXPECT_THROW(bad.Check(), Error);
  bad = rig;
  bad.cam_from_mirror = Rigid3d::Translation(Vec3d(0, 0, -0.01));  // pinhole at z = +0.01, inside the mirror
  EXPECT_THROW(bad.Check(), Error);
  bad = rig;
  bad.mirror.b = std::nan("");
  EXPECT_THROW(bad.Check(), Error);
}

}  // namespace
}  // namespace hovs
