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

// The covariance of the parameters of `blocks` (each block's values in order; a constant block gets zero rows
// and columns), from the Jacobian of every free parameter at the solution: covariance = sigma^2 (J^T J)^+,
// sigma^2 = sum r^2 / (m - p + null_space_rank), the residual variance, so the figures hold for the data's own
// noise level (Ceres' Covariance assumes 1 px). The columns are scaled to unit norm before the SVD, so
// parameters of very different sizes (a focal length and a fourth-order distortion term) do not look rank
// deficient; the null_space_rank smallest singular values (known gauge freedoms) are dropped. False when the rest
// is still rank deficient (reciprocal condition of the scaled Jacobian below 1e-10). `sigma_px`: sigma.
inline bool ParameterCovariance(ceres::Problem* problem, const std::vector<std::pair<double*, int>>& blocks,
                                int null_space_rank, Eigen::MatrixXd* covariance, double* sigma_px = nullptr) {
  std::vector<double*> all, order;
  problem->GetParameterBlocks(&all);
  std::vector<int> listed_col;  // per listed block: its first column in the Jacobian, -1 when constant
  int cols = 0;
  for (const auto& [b, size] : blocks) {
    const bool free = problem->HasParameterBlock(b) && !problem->IsParameterBlockConstant(b);
    listed_col.push_back(free ? cols : -1);
    if (free) order.push_back(b), cols += size;
  }
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
  if (crs.num_rows <= rank || rank < 1) return false;
  Eigen::VectorXd scale = J.colwise().norm().transpose();
  for (int c = 0; c < p; ++c) scale(c) = scale(c) > 0 ? 1.0 / scale(c) : 1.0;
  const Eigen::MatrixXd Js = J * scale.asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  if (!(s(rank - 1) > 1e-10 * s(0))) return false;
  const double sigma2 = 2 * cost / (crs.num_rows - rank);
  if (sigma_px) *sigma_px = std::sqrt(sigma2);
  // Rows of the listed free columns of V S^-1 (unscaled), so that covariance = sigma^2 W W^T.
  const Eigen::MatrixXd W = scale.head(cols).asDiagonal() * svd.matrixV().topLeftCorner(cols, rank) *
                            s.head(rank).cwiseInverse().asDiagonal();
  const Eigen::MatrixXd C = sigma2 * W * W.transpose();
  int total = 0;
  for (const auto& [b, size] : blocks) total += size;
  covariance->setZero(total, total);
  for (size_t a = 0, ra = 0; a < blocks.size(); ra += blocks[a].second, ++a)
    for (size_t b = 0, rb = 0; b < blocks.size(); rb += blocks[b].second, ++b)
      if (listed_col[a] >= 0 && listed_col[b] >= 0)
        covariance->block(ra, rb, blocks[a].second, blocks[b].second) =
            C.block(listed_col[a], listed_col[b], blocks[a].second, blocks[b].second);
  return true;
}

// The standard deviations of the parameters of `blocks`: the square roots of ParameterCovariance's diagonal.
inline bool ParameterStddevs(ceres::Problem* problem, const std::vector<std::pair<double*, int>>& blocks,
                             int null_space_rank, std::vector<std::vector<double>>* stddev) {
  Eigen::MatrixXd C;
  if (!ParameterCovariance(problem, blocks, null_space_rank, &C)) return false;
  stddev->clear();
  int row = 0;
  for (const auto& [b, size] : blocks) {
    std::vector<double> sd;
    for (int k = 0; k < size; ++k, ++row) sd.push_back(std::sqrt(C(row, row)));
    stddev->push_back(sd);
  }
  return true;
}

}  // namespace hovs::calib
