// Derivatives through ceres::Jet match central finite differences for every model, including the ones that
// are inverted numerically (lens undistortion, polynomial world2cam, the law-of-reflection solve).
#include <gtest/gtest.h>

#include <array>

#include "core/catadioptric.h"
#include "core/polynomial.h"
#include "core/model_fit.h"
#include "core/unified.h"
#include "tests/core/test_rigs.h"

namespace hovs {
namespace {

// f: generic callable (const std::array<T, N>&) -> Vec2<T>. Compares the Jet Jacobian with central differences
// (steps relative to each parameter's magnitude) and returns the largest relative discrepancy.
template <int N, class F>
double CompareJacobians(const F& f, const std::array<double, N>& x, const std::array<double, N>& steps) {
  using J = ceres::Jet<double, N>;
  std::array<J, N> xj;
  for (int i = 0; i < N; ++i) xj[i] = J(x[i], i);
  const Vec2<J> yj = f(xj);
  double worst = 0;
  double scale = 0;
  Eigen::Matrix<double, 2, N> jac_fd, jac_jet;
  for (int i = 0; i < N; ++i) {
    std::array<double, N> xp = x, xm = x;
    xp[i] += steps[i];
    xm[i] -= steps[i];
    const Vec2d d = (f(xp) - f(xm)) / (2 * steps[i]);
    for (int r = 0; r < 2; ++r) {
      jac_fd(r, i) = d(r) * steps[i];  // per-step change, comparable across parameters
      jac_jet(r, i) = yj(r).v(i) * steps[i];
    }
  }
  scale = jac_fd.cwiseAbs().maxCoeff();
  worst = (jac_fd - jac_jet).cwiseAbs().maxCoeff() / scale;
  EXPECT_GT(scale, 0);
  return worst;
}

TEST(Jets, ExactSingleViewpointProjection) {
  const auto base = test::AlignedRig();
  const auto f = [&](const auto& p) {
    using T = typename std::decay_t<decltype(p)>::value_type;
    auto rig = base.template Cast<T>();
    rig.mirror.a = p[0], rig.mirror.b = p[1];
    rig.cam_from_mirror.translation = Vec3<T>(T(0), T(0), T(2) * rig.mirror.c());
    Vec2<T> uv;
    EXPECT_EQ(rig.ImgFromMirrorSvp(Vec3<T>(p[2], p[3], p[4]), &uv), ProjectionStatus::kOk);
    return uv;
  };
  EXPECT_LT((CompareJacobians<5>(f, {0.048, 0.044, 1.2, -0.7, -0.9}, {1e-6, 1e-6, 1e-5, 1e-5, 1e-5})), 1e-6);
}

TEST(Jets, GeneralProjectionThroughTheReflectionSolve) {
  const auto base = test::AlignedRig();
  const auto f = [&](const auto& p) {
    using T = typename std::decay_t<decltype(p)>::value_type;
    auto rig = base.template Cast<T>();
    const Rigid3<T> eps(QuaternionFromAngleAxis<T>(Vec3<T>(p[0], p[1], T(0))), Vec3<T>(p[2], T(0.0004), T(0.001)));
    rig.cam_from_mirror = rig.cam_from_mirror * eps;
    Vec2<T> uv;
    EXPECT_EQ(rig.ImgFromMirrorGeneral(Vec3<T>(p[3], p[4], p[5]), &uv), ProjectionStatus::kOk);
    return uv;
  };
  EXPECT_LT((CompareJacobians<6>(f, {0.017, 0.007, 0.001, 2.0, 0.5, -1.1}, {1e-6, 1e-6, 1e-6, 1e-5, 1e-5, 1e-5})),
            1e-6);
}

TEST(Jets, BackProjectionWithLensDistortion) {
  const auto base = test::AlignedRig();
  const auto f = [&](const auto& p) {
    using T = typename std::decay_t<decltype(p)>::value_type;
    auto rig = base.template Cast<T>();
    rig.mirror.a = p[0];
    rig.camera.distortion.k1 = p[1];
    Vec3<T> M, d;
    EXPECT_TRUE(rig.RayFromImg(Vec2<T>(T(1800.3), T(1500.7)), &M, &d));
    return Vec2<T>(d(0) / d(2), d(1) / d(2));
  };
  EXPECT_LT((CompareJacobians<2>(f, {0.048, -0.05}, {1e-7, 1e-6})), 1e-6);
}

TEST(Jets, PolynomialWorldToCamThroughNewton) {
  const auto poly_d = PolynomialFromCatadioptric(test::AlignedRig(), 4);
  const auto f = [&](const auto& p) {
    using T = typename std::decay_t<decltype(p)>::value_type;
    auto m = poly_d.template Cast<T>();
    m.poly[0] = p[0], m.poly[2] = p[1], m.c = p[2];
    Vec2<T> uv;
    EXPECT_TRUE(m.ImgFromCam(Vec3<T>(p[3], p[4], p[5]), &uv));
    return uv;
  };
  const std::array<double, 6> x = {poly_d.poly[0], poly_d.poly[2], 1.0, 1.3, -0.4, -0.8};
  EXPECT_LT((CompareJacobians<6>(f, x, {1e-4 * std::abs(x[0]), 1e-4 * std::abs(x[1]), 1e-6, 1e-5, 1e-5, 1e-5})), 1e-6);
}

TEST(Jets, UnifiedBothDirections) {
  UnifiedModel<double> base;
  base.xi = 0.95, base.fx = 900, base.fy = 901, base.cx = 1374, base.cy = 1099;
  base.distortion = {-0.03, 0.004, 1e-4, 2e-4};
  const auto project = [&](const auto& p) {
    using T = typename std::decay_t<decltype(p)>::value_type;
    auto m = base.template Cast<T>();
    m.xi = p[0], m.distortion.k1 = p[1];
    Vec2<T> uv;
    EXPECT_TRUE(m.ImgFromCam(Vec3<T>(p[2], p[3], p[4]), &uv));
    return uv;
  };
  EXPECT_LT((CompareJacobians<5>(project, {0.95, -0.03, 0.8, 0.3, -0.6}, {1e-6, 1e-6, 1e-5, 1e-5, 1e-5})), 1e-6);
  const auto unproject = [&](const auto& p) {
    using T = typename std::decay_t<decltype(p)>::value_type;
    auto m = base.template Cast<T>();
    m.xi = p[0], m.distortion.k1 = p[1];
    Vec3<T> b = Vec3<T>::Zero();
    EXPECT_TRUE(m.CamFromImg(Vec2<T>(p[2], p[3]), &b));
    return Vec2<T>(b(0) / b(2), b(1) / b(2));
  };
  EXPECT_LT((CompareJacobians<4>(unproject, {0.95, -0.03, 1700.5, 800.25}, {1e-6, 1e-6, 1e-3, 1e-3})), 1e-6);
}

}  // namespace
}  // namespace hovs
