// Board poses as Ceres parameter blocks: [angle-axis (3), translation (3)].
#pragma once

#include <ceres/rotation.h>

#include <array>

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

}  // namespace hovs::calib
