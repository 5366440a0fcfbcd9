// Shared pieces of the calibration problems: board poses as Ceres parameter blocks [angle-axis (3),
// translation (3)], the robust losses by name, and the tight solver settings every calibration uses.
#pragma once

#include <ceres/loss_function.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>

#include <array>
#include <string>

#include "core/rigid.h"

namespace hovs::calib {

inline std::array<double, 6> PoseToParams(const Rigid3d& pose) {
  std::array<double, 6> p;
  const Eigen::Matrix3d R = pose.rotation.toRotationMatrix();
  ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(static_cast<const double*>(R.data())), p.data());
  for (int k = 0; k < 3; ++k) p[3 + k] = pose.translation(k);
  return p;
}

inline Rigid3d ParamsToPose(const double* p) {
  Eigen::Matrix3d R;
  ceres::AngleAxisToRotationMatrix(p, ceres::ColumnMajorAdapter3x3(R.data()));
  return Rigid3d(Eigen::Quaterniond(R), Vec3d(p[3], p[4], p[5]));
}

// "huber" or "cauchy" with its scale (px); nullptr (plain least squares) otherwise. Ceres owns the result.
inline ceres::LossFunction* MakeLoss(const std::string& name, double scale) {
  if (name == "huber") return new ceres::HuberLoss(scale);
  if (name == "cauchy") return new ceres::CauchyLoss(scale);
  return nullptr;
}

// Dense Schur (poses eliminated) with tolerances tight enough that convergence is the solver's own verdict.
inline ceres::Solver::Options CalibrationSolverOptions(int max_iterations, double tolerance) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_SCHUR;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = tolerance;
  so.parameter_tolerance = tolerance;
  so.gradient_tolerance = tolerance;
  return so;
}

}  // namespace hovs::calib
