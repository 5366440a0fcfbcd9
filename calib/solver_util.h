// Shared pieces of the calibration problems: board poses as Ceres parameter blocks [angle-axis (3),
// translation (3)], the robust losses by name, and the tight solver settings every calibration uses.
#pragma once

#include <ceres/crs_matrix.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <string>
#include <vector>

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

// Standard deviations of the parameters of `blocks` (each block's values in order), from the Jacobian of every
// free parameter at the solution: covariance = sigma^2 (J^T J)^+, sigma^2 = sum r^2 / (m - p + null_space_rank),
// the residual variance, so the figures hold for the data's own noise level (Ceres' Covariance assumes 1 px).
// The columns are scaled to unit norm before the SVD, so parameters of very different sizes (a focal length and
// a fourth-order distortion term) do not look rank deficient; the null_space_rank smallest singular values
// (known gauge freedoms) are dropped. False when the rest is still rank deficient (reciprocal condition of the
// scaled Jacobian below 1e-10).
inline bool ParameterStddevs(ceres::Problem* problem, const std::vector<std::pair<double*, int>>& blocks,
                             int null_space_rank, std::vector<std::vector<double>>* stddev) {
  std::vector<double*> all, order;
  problem->GetParameterBlocks(&all);
  for (const auto& [b, size] : blocks) order.push_back(b);
  for (double* b : all)
    if (!problem->IsParameterBlockConstant(b) && std::find(order.begin(), order.end(), b) == order.end())
      order.push_back(b);
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = order;
  double cost = 0;
  ceres::CRSMatrix crs;
  if (!problem->Evaluate(eo, &cost, nullptr, nullptr, &crs)) return false;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) J(r, crs.cols[k]) = crs.values[k];
  const int p = crs.num_cols, rank = p - std::max(0, null_space_rank);
  if (crs.num_rows <= rank) return false;
  Eigen::VectorXd scale = J.colwise().norm().transpose();
  for (int c = 0; c < p; ++c) scale(c) = scale(c) > 0 ? 1.0 / scale(c) : 1.0;
  const Eigen::MatrixXd Js = J * scale.asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  if (!(s(rank - 1) > 1e-10 * s(0))) return false;
  const double sigma2 = 2 * cost / (crs.num_rows - rank);
  stddev->clear();
  int col = 0;
  for (const auto& [b, size] : blocks) {
    std::vector<double> sd;
    for (int k = 0; k < size; ++k, ++col) {
      double var = 0;
      for (int j = 0; j < rank; ++j) var += std::pow(svd.matrixV()(col, j) / s(j), 2);
      sd.push_back(std::sqrt(sigma2 * var) * scale(col));
    }
    stddev->push_back(sd);
  }
  return true;
}

}  // namespace hovs::calib
