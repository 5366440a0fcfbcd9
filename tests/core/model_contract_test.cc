// One contract, run on every camera model of the core (as COLMAP's and Sophus' model tests do): for pixels of
// the model's domain, back-projection gives a unit bearing and projecting a point on that ray gives the pixel
// back; the projection's Jacobian through ceres::Jet matches central finite differences; and the domain's edges
// hold: a pixel outside the image does not back-project, a point behind the model does not project.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/catadioptric.h"
#include "core/model_fit.h"
#include "core/pinhole.h"
#include "core/polynomial.h"
#include "core/unified.h"
#include "tests/core/test_rigs.h"

namespace hovs {
namespace {

// The adapters give every model one interface: a ray (origin, unit direction) from a pixel, a pixel from a point,
// the domain, and a point the model cannot see.
struct PinholeCase {
  static constexpr bool kRayRefusesOutside = false;
  PinholeCamera<double> model = [] {
    auto c = test::ReferenceCamera();
    c.distortion = {-0.08, 0.02, 1e-4, -2e-4};
    return c;
  }();
  template <class T>
  static bool Project(const PinholeCamera<T>& m, const Vec3<T>& X, Vec2<T>* uv) {
    return m.ImgFromCam(X, uv);
  }
  bool Ray(const Vec2d& uv, Vec3d* origin, Vec3d* d) const {
    *origin = Vec3d::Zero();
    return model.CamFromImg(uv, d);
  }
  bool InDomain(const Vec2d& uv) const { return (uv - Vec2d(model.cx, model.cy)).norm() < 600; }
  Vec3d Unseen() const { return Vec3d(0.1, 0.2, -1.0); }  // behind the camera
  int width() const { return model.width; }
  int height() const { return model.height; }
};

struct PolynomialCase {
  static constexpr bool kRayRefusesOutside = false;
  PolynomialModel<double> model = PolynomialFromCatadioptric(test::AlignedRig(), 5);
  template <class T>
  static bool Project(const PolynomialModel<T>& m, const Vec3<T>& X, Vec2<T>* uv) {
    return m.ImgFromCam(X, uv);
  }
  bool Ray(const Vec2d& uv, Vec3d* origin, Vec3d* d) const {
    *origin = Vec3d::Zero();
    return model.CamFromImg(uv, d);
  }
  bool InDomain(const Vec2d& uv) const {
    const double rho = model.RhoOfImg(uv);
    return rho >= model.rho_min && rho <= model.rho_max && uv.x() >= 0 && uv.y() >= 0 && uv.x() < model.width &&
           uv.y() < model.height;
  }
  Vec3d Unseen() const { return Vec3d(0.0, 0.0, 1.0); }  // straight up the axis, into the mirror's own image
  int width() const { return model.width; }
  int height() const { return model.height; }
};

struct UnifiedCase {
  static constexpr bool kRayRefusesOutside = false;
  UnifiedModel<double> model = UnifiedFromCatadioptric(test::AlignedRig());
  template <class T>
  static bool Project(const UnifiedModel<T>& m, const Vec3<T>& X, Vec2<T>* uv) {
    return m.ImgFromCam(X, uv);
  }
  bool Ray(const Vec2d& uv, Vec3d* origin, Vec3d* d) const {
    *origin = Vec3d::Zero();
    return model.CamFromImg(uv, d);
  }
  bool InDomain(const Vec2d& uv) const { return (uv - Vec2d(model.cx, model.cy)).norm() < 900; }
  Vec3d Unseen() const { return Vec3d(0.0, 0.0, 1.0); }  // up the axis: outside z < xi |X| (mirror frame)
  int width() const { return model.width; }
  int height() const { return model.height; }
};

template <bool kMisaligned>
struct ExactCase {
  static constexpr bool kRayRefusesOutside = true;
  CatadioptricCamera<double> model = kMisaligned ? test::MisalignedRig() : test::AlignedRig();
  template <class T>
  static bool Project(const CatadioptricCamera<T>& m, const Vec3<T>& X, Vec2<T>* uv) {
    return m.ImgFromMirror(X, uv) == ProjectionStatus::kOk;
  }
  bool Ray(const Vec2d& uv, Vec3d* origin, Vec3d* d) const { return model.RayFromImg(uv, origin, d); }
  bool InDomain(const Vec2d& uv) const { return model.SeesMirror(uv); }
  Vec3d Unseen() const { return Vec3d(0.0, 0.0, 1.0); }  // straight into the mirror's axis: the camera's image
  int width() const { return model.camera.width; }
  int height() const { return model.camera.height; }
};

template <class Case>
class ModelContract : public ::testing::Test {};
using Cases = ::testing::Types<PinholeCase, PolynomialCase, UnifiedCase, ExactCase<false>, ExactCase<true>>;
TYPED_TEST_SUITE(ModelContract, Cases);

TYPED_TEST(ModelContract, RoundTripOverTheDomain) {
  const TypeParam c;
  const int step = std::max(1, c.width() / 60);
  int n = 0;
  double worst = 0;
  for (int v = 0; v < c.height(); v += step)
    for (int u = 0; u < c.width(); u += step) {
      const Vec2d uv(u + 0.25, v + 0.5);
      if (!c.InDomain(uv)) continue;
      Vec3d origin, d;
      ASSERT_TRUE(c.Ray(uv, &origin, &d)) << uv.transpose();
      EXPECT_NEAR(d.norm(), 1.0, 1e-12);
      Vec2d back;
      ASSERT_TRUE(TypeParam::Project(c.model, Vec3d(origin + 3.7 * d), &back)) << uv.transpose();
      worst = std::max(worst, (back - uv).norm());
      ++n;
    }
  EXPECT_GT(n, 500);
  EXPECT_LT(worst, 1e-6);
}

TYPED_TEST(ModelContract, JacobianMatchesFiniteDifferences) {
  const TypeParam c;
  using J = ceres::Jet<double, 3>;
  const auto model_j = c.model.template Cast<J>();
  int compared = 0;
  for (const Vec2d& uv : {Vec2d(0.3 * c.width(), 0.5 * c.height()), Vec2d(0.5 * c.width(), 0.8 * c.height()),
                          Vec2d(0.62 * c.width(), 0.31 * c.height())}) {
    Vec3d origin, d;
    if (!c.InDomain(uv) || !c.Ray(uv, &origin, &d)) continue;
    const Vec3d X = origin + 2.0 * d;
    Vec3<J> Xj;
    for (int i = 0; i < 3; ++i) Xj(i) = J(X(i), i);
    Vec2<J> uvj;
    ASSERT_TRUE(TypeParam::Project(model_j, Xj, &uvj));
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i) {
      Vec3d Xp = X, Xm = X;
      Xp(i) += h, Xm(i) -= h;
      Vec2d up, um;
      ASSERT_TRUE(TypeParam::Project(c.model, Xp, &up) && TypeParam::Project(c.model, Xm, &um));
      const Vec2d fd = (up - um) / (2 * h);
      for (int r = 0; r < 2; ++r) EXPECT_NEAR(uvj(r).v(i), fd(r), 1e-4 * (1 + std::abs(fd(r)))) << i << "," << r;
    }
    EXPECT_NEAR(uvj(0).a, Vec2d(uv)(0), 1e-6);
    ++compared;
  }
  EXPECT_GE(compared, 1);
}

TYPED_TEST(ModelContract, DomainEdges) {
  const TypeParam c;
  Vec2d uv;
  EXPECT_FALSE(TypeParam::Project(c.model, c.Unseen(), &uv)) << uv.transpose();
  // The image corner lies outside every model's domain; the exact rig refuses its ray itself (no mirror there),
  // the analytic models leave the domain to their annulus (AnyModel::InImage and InAnnulus).
  const Vec2d corner(0.5, 0.5);
  EXPECT_FALSE(c.InDomain(corner));
  Vec3d origin, d;
  if (TypeParam::kRayRefusesOutside) { EXPECT_FALSE(c.Ray(corner, &origin, &d)); }
}

}  // namespace
}  // namespace hovs
