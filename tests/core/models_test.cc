// Pinhole, unified and polynomial models: round trips for every model, the unified model from a design, the
// polynomial fitted to the exact model.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <memory>

#include "core/any_model.h"
#include "core/model_fit.h"
#include "core/pinhole.h"
#include "core/polynomial.h"
#include "core/unified.h"
#include "tests/core/test_rigs.h"

namespace hovs {
namespace {

// Every model: pixel -> bearing -> pixel over the valid pixels, in double.
template <class Model, class Valid>
double WorstRoundTrip(const Model& model, int width, int height, int step, const Valid& valid, int* count) {
  double worst = 0;
  *count = 0;
  for (int v = 0; v < height; v += step)
    for (int u = 0; u < width; u += step) {
      const Vec2d uv(u + 0.3, v + 0.6);
      if (!valid(uv)) continue;
      Vec3d bearing = Vec3d::Zero();
      EXPECT_TRUE(model.CamFromImg(uv, &bearing)) << uv.transpose();
      EXPECT_NEAR(bearing.norm(), 1.0, 1e-14);
      Vec2d back = Vec2d::Zero();
      EXPECT_TRUE(model.ImgFromCam(bearing * 3.7, &back)) << uv.transpose();
      worst = std::max(worst, (back - uv).norm());
      ++*count;
    }
  return worst;
}

TEST(Pinhole, RoundTripWithDistortion) {
  auto cam = test::ReferenceCamera();
  cam.distortion = {-0.12, 0.03, 2e-4, -1e-4};
  int n = 0;
  const double worst = WorstRoundTrip(
      cam, cam.width, cam.height, 41, [](const Vec2d&) { return true; }, &n);
  EXPECT_GT(n, 3000);
  EXPECT_LT(worst, 1e-9);
  Vec2d uv = Vec2d::Zero();
  EXPECT_FALSE(cam.ImgFromCam(Vec3d(0, 0, -1), &uv)) << "behind the camera";
}

TEST(Unified, RoundTripWithDistortionAndSkew) {
  UnifiedModel<double> m;
  m.width = 1024, m.height = 768;
  m.xi = 0.96, m.fx = 300, m.fy = 298, m.cx = 512.3, m.cy = 380.1, m.skew = 0.2;
  m.distortion = {-0.05, 0.01, 1e-3, -5e-4};
  int n = 0;
  const auto valid = [&](const Vec2d& uv) { return (uv - Vec2d(m.cx, m.cy)).norm() < 380; };
  const double worst = WorstRoundTrip(m, m.width, m.height, 7, valid, &n);
  EXPECT_GT(n, 5000);
  EXPECT_LT(worst, 1e-9);
}

TEST(Unified, FromDesignReproducesTheExactProjection) {
  for (bool with_distortion : {false, true}) {
    auto rig = test::AlignedRig();
    if (with_distortion) rig.camera.distortion = {-0.08, 0.02, 1e-4, -2e-4};
    const UnifiedModel<double> u = UnifiedFromCatadioptric(rig);
    EXPECT_GT(u.xi, 0.9);
    EXPECT_LT(u.xi, 1.0);
    double worst = 0;
    int compared = 0;
    for (const Vec3d& X : test::WorldPoints(2000, 3)) {
      Vec2d exact = Vec2d::Zero(), unified = Vec2d::Zero();
      if (rig.ImgFromMirror(X, &exact) != ProjectionStatus::kOk) continue;
      ASSERT_TRUE(u.ImgFromCam(X, &unified));
      worst = std::max(worst, (exact - unified).norm());
      ++compared;
    }
    EXPECT_GT(compared, 1500);
    EXPECT_LT(worst, 1e-6) << "distortion " << with_distortion;
    int n = 0;
    EXPECT_LT(WorstRoundTrip(
                  u, rig.camera.width, rig.camera.height, 43, [&](const Vec2d& uv) { return rig.SeesMirror(uv); }, &n),
              1e-9);
    EXPECT_GT(n, 1000);
  }
  auto tilted = test::MisalignedRig();
  EXPECT_THROW(UnifiedFromCatadioptric(tilted), Error);
}

// Solvers project with ImgFromPointUnbounded: inside a model's domain it is ImgFromMirror (of a point at the
// exact model's scene distance, where ImgFromMirror puts bearings); past the domain's
// edge (the rim, the annulus) it goes on smoothly instead of failing, so that a corner observed near the rim
// does not stop a solve whose iterate carries it just past.
TEST(AnyModel, UnboundedProjectionIsTheBoundedOneInsideAndContinuesPastTheRim) {
  const auto rig = test::AlignedRig();
  const PolynomialModel<double> poly = PolynomialFromCatadioptric(rig, 4);
  const std::vector<std::pair<std::string, AnyModel>> models = {
      {"exact", AnyModel::Exact(rig)},
      {"exact, misaligned", AnyModel::Exact(test::MisalignedRig(), 3.0)},
      {"polynomial", AnyModel::Polynomial(poly)},
      {"unified", AnyModel::Unified(UnifiedFromCatadioptric(rig), poly.rho_min, poly.rho_max)}};
  const double deg = M_PI / 180, step = 0.05 * deg;
  const auto bearing = [](double az, double el) {
    return Vec3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  };
  for (const auto& [name, m] : models)
    for (double az : {0.3, 2.0, -2.2}) {
      // The first elevation (upwards from -60 deg) that leaves the model's domain.
      double edge = -60 * deg;
      Vec2d uv, ub;
      while (edge < 60 * deg && m.ImgFromMirror(bearing(az, edge), &uv)) {
        ASSERT_TRUE(m.ImgFromPointUnbounded(m.scene_distance() * bearing(az, edge), &ub)) << name;
        EXPECT_LT((ub - uv).norm(), 1e-9) << name << " at elevation " << edge / deg;
        edge += step;
      }
      ASSERT_LT(edge, 60 * deg) << name << ": the domain has no upper edge";
      EXPECT_GT(edge, -30 * deg) << name;
      // Seven pixels 0.05 deg apart, three inside the domain and four outside: evenly spaced to 1 %.
      std::vector<Vec2d> p(7);
      for (int k = 0; k < 7; ++k)
        ASSERT_TRUE(m.ImgFromPointUnbounded(m.scene_distance() * bearing(az, edge + (k - 3) * step), &p[k]))
            << name << " k " << k;
      for (int k = 1; k < 6; ++k) {
        const double d = (p[k + 1] - p[k]).norm();
        EXPECT_GT(d, 0.1) << name;
        EXPECT_LT((p[k + 1] - 2 * p[k] + p[k - 1]).norm(), 0.01 * d) << name << " at " << k;
      }
    }
}

TEST(Polynomial, Degree4FitReproducesTheExactModelOverTheMirror) {
  const auto rig = test::AlignedRig();
  const PolynomialModel<double> poly = PolynomialFromCatadioptric(rig, 4);
  EXPECT_LT(poly.poly[0], 0) << "a0 < 0: the centre looks down";
  EXPECT_EQ(poly.poly[1], 0);
  double worst = 0;
  int compared = 0;
  for (const Vec3d& X : test::WorldPoints(4000, 5)) {
    Vec2d exact = Vec2d::Zero(), fitted = Vec2d::Zero();
    if (rig.ImgFromMirror(X, &exact) != ProjectionStatus::kOk) continue;
    ASSERT_TRUE(poly.ImgFromCam(X, &fitted));
    worst = std::max(worst, (exact - fitted).norm());
    ++compared;
  }
  EXPECT_GT(compared, 3000);
  EXPECT_LT(worst, 0.02);
  RecordProperty("degree4_worst_px", std::to_string(worst));
}

TEST(Polynomial, ExactAndFastWorldToCamRoundTrips) {
  const auto rig = test::AlignedRig();
  PolynomialModel<double> poly = PolynomialFromCatadioptric(rig, 5);
  poly.c = 1.0004, poly.d = -0.0003, poly.e = 0.0002;  // a slightly affine sensor
  const double fit_err = poly.FitInverse(0.01);
  EXPECT_LT(fit_err, 0.01);
  const auto in_annulus = [&](const Vec2d& uv) {
    const double rho = poly.RhoOfImg(uv);
    return rho >= poly.rho_min && rho <= poly.rho_max;
  };
  int n = 0;
  EXPECT_LT(WorstRoundTrip(poly, rig.camera.width, rig.camera.height, 29, in_annulus, &n), 1e-9);
  EXPECT_GT(n, 3000);
  double worst_fast = 0;
  for (int v = 0; v < rig.camera.height; v += 31)
    for (int u = 0; u < rig.camera.width; u += 31) {
      const Vec2d uv(u, v);
      if (!in_annulus(uv)) continue;
      Vec3d b = Vec3d::Zero();
      ASSERT_TRUE(poly.CamFromImg(uv, &b));
      Vec2d back = Vec2d::Zero();
      ASSERT_TRUE(poly.ImgFromCamFast(b, &back));
      worst_fast = std::max(worst_fast, (back - uv).norm());
    }
  EXPECT_LT(worst_fast, 0.01);
}

// A near-parabolic camera whose field reaches 40 degrees above the horizon (xi = 1: f(rho) is exactly
// quadratic), and the same with a quartic term that makes theta(rho) fold just past the annulus: the inverse's
// fit never throws, records its accuracy, and ImgFromCam stays exact.
TEST(Polynomial, InverseOfAWideFieldModelIsStableAndNeverFatal) {
  const auto check = [](PolynomialModel<double>* model, double expect_fast_below_px) {
    PolynomialModel<double>& m = *model;
    m.width = 700, m.height = 700, m.cx = 349.5, m.cy = 349.5;
    ASSERT_NO_THROW(m.FitInverse(0.01));
    EXPECT_TRUE(std::isfinite(m.inv_error_px));
    EXPECT_LT(m.inv_error_px, expect_fast_below_px);
    EXPECT_LE(m.inv_error_px, m.inv_poly_error_px + 1e-12) << "Chebyshev is at least as good as monomials";
    double worst = 0, worst_fast = 0;
    int n = 0;
    for (int k = 0; k <= 200; ++k) {
      const double rho = m.rho_min + (m.rho_max - m.rho_min) * k / 200, phi = 0.37 * k;
      const Vec2d uv(m.cx + rho * std::cos(phi), m.cy + rho * std::sin(phi));
      Vec3d b;
      Vec2d back, fast;
      ASSERT_TRUE(m.CamFromImg(uv, &b));
      ASSERT_TRUE(m.ImgFromCam(b, &back)) << "rho " << rho;
      ASSERT_TRUE(m.ImgFromCamFast(b, &fast));
      worst = std::max(worst, (back - uv).norm()), worst_fast = std::max(worst_fast, (fast - uv).norm());
      ++n;
    }
    EXPECT_LT(worst, 1e-7);
    EXPECT_LE(worst_fast, m.inv_error_px + 1e-6);
  };
  PolynomialModel<double> parabolic;
  parabolic.poly = {-75, 0, 1.0 / 300};  // h = 150 px; theta = +40 deg at rho = h (1 + sin 40) / cos 40 = 322 px
  parabolic.rho_min = 2, parabolic.rho_max = 322;
  check(&parabolic, 0.01);
  EXPECT_GT(parabolic.inv_theta_hi * 180 / M_PI, 39.9);
  // dtheta/drho = 0 at rho = 300 px (f' rho = f): the inverse is vertical there.
  PolynomialModel<double> folding;
  folding.poly = {-75, 0, 1.0 / 300, 0, -375.0 / (3 * 8.1e9)};
  folding.rho_min = 2, folding.rho_max = 299.9;
  check(&folding, 5.0);
  // The calibration's annulus stops short of the fold, where theta is still well defined.
  folding.rho_min = 2, folding.rho_max = 299.9;
  ASSERT_TRUE(folding.SetAnnulusWithin(20, 280, 2, 14));
  EXPECT_GT(folding.rho_max, 280);
  EXPECT_LT(folding.rho_max, 299);
  EXPECT_NEAR(folding.rho_min, 18, 1e-9);
  check(&folding, 1.0);
  EXPECT_FALSE(folding.SetAnnulusWithin(20, 320, 2, 14)) << "folds inside the data";
}

// ImgFromCamBatch (blocks of points, lanes innermost) gives ImgFromCam's pixel and status for every point: the
// reference unit's model with an affine sensor, a model whose inverse is only good to pixels (Newton from a far
// start), one without any inverse (every point takes the scalar path), and points on the axis, at the origin,
// not finite or behind the camera, in a count that is not a multiple of the block.
TEST(Polynomial, BatchProjectionIsTheScalarOne) {
  const auto compare = [](const PolynomialModel<double>& m, const std::vector<Vec3d>& points, const char* name) {
    std::vector<double> X, uv(2 * points.size(), -1.0);
    for (const Vec3d& p : points) X.insert(X.end(), {p(0), p(1), p(2)});
    std::unique_ptr<bool[]> ok(new bool[points.size()]);
    m.ImgFromCamBatch(X.data(), points.size(), uv.data(), ok.get());
    int agreed = 0, valid = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      Vec2d q;
      const bool scalar = m.ImgFromCam(points[i], &q);
      ASSERT_EQ(ok[i], scalar) << name << " point " << i << ": " << points[i].transpose();
      if (!scalar) continue;
      ++valid;
      EXPECT_LT((Vec2d(uv[2 * i], uv[2 * i + 1]) - q).norm(), 1e-9) << name << " point " << i;
      agreed += (Vec2d(uv[2 * i], uv[2 * i + 1]) - q).norm() < 1e-9;
    }
    EXPECT_GT(valid, static_cast<int>(points.size()) / 2) << name;
    RecordProperty(std::string(name) + "_agreed", agreed);
  };
  const auto rig = test::AlignedRig();
  PolynomialModel<double> poly = PolynomialFromCatadioptric(rig, 5);
  poly.c = 1.0004, poly.d = -0.0003, poly.e = 0.0002;
  poly.FitInverse(0.01);
  std::vector<Vec3d> points = test::WorldPoints(1000, 7);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  points.insert(points.begin() + 5, {Vec3d(0, 0, -1), Vec3d(0, 0, 1), Vec3d(0, 0, 0), Vec3d(nan, 0, 1),
                                     Vec3d(1, HUGE_VAL, 0), Vec3d(1e-300, 0, -1), Vec3d(0.3, -0.2, 1e6)});
  points.resize(1003);
  compare(poly, points, "reference");
  PolynomialModel<double> coarse = poly;  // a 3-term inverse: a start several pixels off
  coarse.inv_cheb.resize(3);
  compare(coarse, points, "coarse_inverse");
  PolynomialModel<double> none = poly;
  none.inv_cheb.clear();
  compare(none, points, "no_chebyshev");
  PolynomialModel<double> decentred = poly;
  decentred.p1 = 4e-4, decentred.p2 = -6e-4;
  compare(decentred, points, "decentred");
}

// The decentering extension: CamFromImg and ImgFromCam invert each other to rounding, the image moves by the
// Brown-Conrady displacement (a few pixels at the rim for p ~ 5e-4), and the model's check bounds p1, p2.
TEST(Polynomial, DecenteringRoundTripsAndMovesTheImageAsBrownConrady) {
  const auto rig = test::AlignedRig();
  PolynomialModel<double> plain = PolynomialFromCatadioptric(rig, 5);
  PolynomialModel<double> m = plain;
  m.p1 = 5e-4, m.p2 = -3e-4;
  EXPECT_NO_THROW(m.Check());
  double worst = 0, largest_shift = 0;
  int n = 0;
  for (const Vec3d& X : test::WorldPoints(2000, 9)) {
    Vec2d uv, uv_plain;
    if (!plain.ImgFromCam(X, &uv_plain)) continue;
    ASSERT_TRUE(m.ImgFromCam(X, &uv));
    const double rho = m.RhoOfImg(uv);
    if (rho < m.rho_min || rho > m.rho_max) continue;
    Vec3d b;
    ASSERT_TRUE(m.CamFromImg(uv, &b));
    worst = std::max(worst, std::atan2(b.cross(X.normalized()).norm(), b.dot(X.normalized())));
    // The shift is Brown-Conrady's on (p_c, p_r) / |a0| (columns first), scaled back.
    const double s = -m.poly[0];
    const double x = (uv_plain.x() - m.cx) / s, y = (uv_plain.y() - m.cy) / s, r2 = x * x + y * y;
    const Vec2d expect(s * (2 * m.p1 * x * y + m.p2 * (r2 + 2 * x * x)),
                       s * (m.p1 * (r2 + 2 * y * y) + 2 * m.p2 * x * y));
    EXPECT_LT((uv - uv_plain - expect).norm(), 1e-6) << X.transpose();
    largest_shift = std::max(largest_shift, (uv - uv_plain).norm());
    ++n;
  }
  EXPECT_GT(n, 1000);
  EXPECT_LT(worst, 1e-12) << "rad";
  EXPECT_GT(largest_shift, 1.0) << "px";
  m.p2 = 0.2;
  EXPECT_THROW(m.Check(), Error);
}

TEST(Polynomial, CheckAndInverseRejectBadModels) {
  PolynomialModel<double> m;
  m.poly = {-200, 0.1, 1e-3};
  EXPECT_THROW(m.Check(), Error) << "a1 must be zero";
  m.poly = {-200, 0, 1e-3};
  EXPECT_NO_THROW(m.Check());
  m.rho_min = 10, m.rho_max = 5;
  EXPECT_THROW(m.FitInverse(), Error);
  // theta(rho) folds back: no inverse over this annulus.
  m.poly = {-200, 0, 0.01, -2e-5};
  m.rho_min = 1, m.rho_max = 1000;
  EXPECT_THROW(m.FitInverse(), Error);
}

TEST(Models, CheckRefusesWhatNoCameraHas) {
  // Each of these once loaded and gave blank views with exit 0.
  PolynomialModel<double> p;
  p.width = 1024, p.height = 768, p.cx = 511.5, p.cy = 383.5, p.poly = {-200, 0, 1e-3}, p.rho_min = 0, p.rho_max = 400;
  EXPECT_NO_THROW(p.Check());
  const auto poly_refused = [&](const std::function<void(PolynomialModel<double>*)>& spoil) {
    PolynomialModel<double> q = p;
    spoil(&q);
    EXPECT_THROW(q.Check("model.json"), Error);
  };
  poly_refused([](auto* q) { q->poly = {0, 0, 0, 0, 0}; });
  poly_refused([](auto* q) { q->cx = 1e9; });
  poly_refused([](auto* q) { q->cy = NAN; });
  poly_refused([](auto* q) { q->c = 1e308; });
  poly_refused([](auto* q) { q->poly[2] = 1e308; });  // f(rho) overflows over the annulus
  poly_refused([](auto* q) { q->rho_max = 1e9; });
  poly_refused([](auto* q) { q->inv_poly = {1, NAN}; });
  poly_refused([](auto* q) { q->width = -3; });
  UnifiedModel<double> u;
  u.width = 1024, u.height = 768, u.xi = 0.9, u.fx = u.fy = 300, u.cx = 511.5, u.cy = 383.5;
  EXPECT_NO_THROW(u.Check());
  for (auto spoil : std::vector<std::function<void(UnifiedModel<double>*)>>{
           [](auto* m) { m->xi = NAN; }, [](auto* m) { m->fx = 1e308; }, [](auto* m) { m->cx = 1e9; },
           [](auto* m) { m->distortion.k1 = INFINITY; }, [](auto* m) { m->skew = NAN; }}) {
    UnifiedModel<double> m = u;
    spoil(&m);
    EXPECT_THROW(m.Check(), Error);
  }
  CatadioptricCamera<double> rig = test::AlignedRig();
  EXPECT_NO_THROW(rig.Check());
  for (auto spoil : std::vector<std::function<void(CatadioptricCamera<double>*)>>{
           [](auto* r) { r->mirror.a = 1e308; }, [](auto* r) { r->camera.fx = 1e308; },
           [](auto* r) { r->camera.cx = -1e9; }, [](auto* r) { r->cam_from_mirror.translation.x() = NAN; },
           [](auto* r) { r->cam_from_mirror.rotation.coeffs() *= 3; }}) {
    CatadioptricCamera<double> r = rig;
    spoil(&r);
    EXPECT_THROW(r.Check(), Error);
  }
}

}  // namespace
}  // namespace hovs
