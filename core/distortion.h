// Radial-tangential lens distortion (Brown-Conrady, OpenCV's k1, k2, p1, p2), on normalised image coordinates.
//
//   r^2 = x^2 + y^2
//   x_d = x (1 + k1 r^2 + k2 r^4) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4) + p1 (r^2 + 2 y^2) + 2 p2 x y
//
// Valid domain: where the map is invertible, i.e. its Jacobian stays non-singular between the origin and the
// point; Undistort returns false when Newton's method does not converge there.
#pragma once

#include "core/error.h"
#include "core/newton.h"
#include "core/types.h"

namespace hovs {

template <class T>
struct RadTanDistortion {
  T k1 = T(0), k2 = T(0), p1 = T(0), p2 = T(0);

  bool IsZero() const {
    return ScalarPart(k1) == 0 && ScalarPart(k2) == 0 && ScalarPart(p1) == 0 && ScalarPart(p2) == 0;
  }

  // Finite coefficients of a plausible size (|k| <= 100: a lens whose distortion moves a point at the edge of
  // the field by more than that many times its distance is not a radial-tangential lens).
  void Check(const std::string& where) const {
    for (const T& v : {k1, k2, p1, p2})
      HOVS_REQUIRE(std::isfinite(ScalarPart(v)) && std::abs(ScalarPart(v)) <= 100, where,
                   "distortion coefficients must be finite and within +-100 (got ", ScalarPart(v), ")");
  }

  template <class S>
  Vec2<S> Distort(const Vec2<S>& m) const {
    const S x = m(0), y = m(1);
    const S r2 = x * x + y * y;
    const S radial = S(1) + S(k1) * r2 + S(k2) * r2 * r2;
    return Vec2<S>(x * radial + S(2) * S(p1) * x * y + S(p2) * (r2 + S(2) * x * x),
                   y * radial + S(p1) * (r2 + S(2) * y * y) + S(2) * S(p2) * x * y);
  }

  // Inverse of Distort by Newton's method (solved in double, lifted to T).
  bool Undistort(const Vec2<T>& md, Vec2<T>* m) const {
    if (IsZero()) {
      *m = md;
      return true;
    }
    const RadTanDistortion<double> dd = Cast<double>();
    const Vec2d target = ConvertMatrix<double>(md);
    Vec2d x = target;
    NewtonOptions options;
    options.residual_tolerance = 1e-15;
    const auto residual = [&](const auto& p) {
      using S = typename std::decay_t<decltype(p)>::Scalar;
      const Vec2<S> t(S(target(0)), S(target(1)));
      return Vec2<S>(dd.Distort(p) - t);
    };
    const NewtonResult r = SolveNewton2(residual, &x, options);
    if (!r.converged || r.residual_norm > 1e-12) return false;
    const auto residual_t = [&](const Vec2<T>& p) { return Vec2<T>(Distort(p) - md); };
    *m = LiftNewton2<T>(residual_t, x, r.jacobian);
    return true;
  }

  template <class U>
  RadTanDistortion<U> Cast() const {
    return {ConvertScalar<U>(k1), ConvertScalar<U>(k2), ConvertScalar<U>(p1), ConvertScalar<U>(p2)};
  }
};

}  // namespace hovs
