// Newton solvers for the small inversions in the models (lens undistortion, polynomial world2cam, the
// law-of-reflection point). They solve in double with Jacobians from ceres::Jet, and LiftNewton2/LiftNewton1
// carry the double solution to any scalar type T with one Newton step, which gives exact first derivatives
// (implicit function theorem) when T is a Jet.
#pragma once

#include <Eigen/LU>
#include <cmath>

#include "core/types.h"

namespace hovs {

struct NewtonOptions {
  int max_iterations = 50;
  double residual_tolerance = 1e-14;  // stop when |F| is below this (absolute)
  double step_tolerance = 1e-15;      // stop when the step is below this (relative to |x| + 1)
  double max_step = 0;                // > 0: clamp each step's length (damping for far starts)
};

struct NewtonResult {
  bool converged = false;
  int iterations = 0;
  double residual_norm = 0;
  Mat2<double> jacobian = Mat2<double>::Identity();
};

// Solves residual(x) = 0 for x in R^2. residual is callable with Vec2<double> and Vec2<Jet<double,2>>.
// Backtracking keeps |F| from growing. Returns the state at exit; x is updated in place.
template <class Residual>
NewtonResult SolveNewton2(const Residual& residual, Vec2d* x, const NewtonOptions& options = {}) {
  using J2 = ceres::Jet<double, 2>;
  NewtonResult result;
  for (int it = 0; it < options.max_iterations; ++it) {
    Vec2<J2> xj(J2((*x)(0), 0), J2((*x)(1), 1));
    const Vec2<J2> fj = residual(xj);
    Vec2d f(fj(0).a, fj(1).a);
    for (int r = 0; r < 2; ++r) result.jacobian.row(r) = fj(r).v.transpose();
    result.residual_norm = f.norm();
    result.iterations = it;
    if (!std::isfinite(result.residual_norm)) return result;
    if (result.residual_norm <= options.residual_tolerance) {
      result.converged = true;
      return result;
    }
    const double det = result.jacobian.determinant();
    if (!std::isfinite(det) || std::abs(det) < 1e-300) return result;
    Vec2d step = -result.jacobian.inverse() * f;
    if (options.max_step > 0 && step.norm() > options.max_step) step *= options.max_step / step.norm();
    // Backtracking: accept the first step length that does not increase |F|.
    double scale = 1.0;
    Vec2d candidate = *x + step;
    for (int k = 0; k < 30; ++k) {
      const Vec2d fc = residual(candidate);
      if (std::isfinite(fc.norm()) && fc.norm() <= result.residual_norm) break;
      scale *= 0.5;
      candidate = *x + scale * step;
    }
    *x = candidate;
    if ((scale * step).norm() <= options.step_tolerance * (x->norm() + 1.0)) {
      const Vec2d fe = residual(*x);
      result.residual_norm = fe.norm();
      result.converged = std::isfinite(result.residual_norm);
      return result;
    }
  }
  const Vec2d fe = residual(*x);
  result.residual_norm = fe.norm();
  return result;
}

// Solves residual(x) = 0 for scalar x. residual is callable with double and Jet<double,1>.
template <class Residual>
bool SolveNewton1(const Residual& residual, double* x, double* derivative, const NewtonOptions& options = {}) {
  using J1 = ceres::Jet<double, 1>;
  for (int it = 0; it < options.max_iterations; ++it) {
    const J1 fj = residual(J1(*x, 0));
    *derivative = fj.v(0);
    if (!std::isfinite(fj.a)) return false;
    if (std::abs(fj.a) <= options.residual_tolerance) return true;
    if (!std::isfinite(*derivative) || *derivative == 0.0) return false;
    double step = -fj.a / *derivative;
    if (options.max_step > 0 && std::abs(step) > options.max_step) step = std::copysign(options.max_step, step);
    *x += step;
    if (std::abs(step) <= options.step_tolerance * (std::abs(*x) + 1.0)) {
      *derivative = residual(J1(*x, 0)).v(0);
      return true;
    }
  }
  return std::abs(residual(*x)) <= 1e3 * options.residual_tolerance;
}

// One Newton step in scalar type T from the double solution x0 of F(x) = 0, with J = dF/dx at x0.
// residual_t evaluates F with the T-typed parameters. For T = double this is a polishing step.
template <class T, class ResidualT>
Vec2<T> LiftNewton2(const ResidualT& residual_t, const Vec2d& x0, const Mat2<double>& jacobian) {
  const Vec2<T> xt(T(x0(0)), T(x0(1)));
  const Vec2<T> f = residual_t(xt);
  const Mat2<double> inv = jacobian.inverse();
  Vec2<T> out;
  out(0) = xt(0) - (T(inv(0, 0)) * f(0) + T(inv(0, 1)) * f(1));
  out(1) = xt(1) - (T(inv(1, 0)) * f(0) + T(inv(1, 1)) * f(1));
  return out;
}

template <class T, class ResidualT>
T LiftNewton1(const ResidualT& residual_t, double x0, double derivative) {
  const T xt(x0);
  return xt - residual_t(xt) / T(derivative);
}

}  // namespace hovs
