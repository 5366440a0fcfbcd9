#include "calib/board_pose.h"

#include <ceres/ceres.h>

#include <cmath>
#include <opencv2/calib3d.hpp>

namespace hovs::calib {
namespace {

// Pose as a unit quaternion (x, y, z, w: Eigen's storage) and a translation.
Rigid3d ToPose(const double* q, const double* t) {
  return Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(), Vec3d(t[0], t[1], t[2]));
}

struct PointCost {
  const AnyModel* model;
  Vec3d X;
  Vec2d obs;
  bool operator()(const double* q, const double* t, double* r) const {
    Vec2d uv;
    if (!model->ImgFromPointUnbounded(ToPose(q, t) * X, &uv)) return false;
    r[0] = uv(0) - obs(0), r[1] = uv(1) - obs(1);
    return true;
  }
};

}  // namespace

double BoardReprojectionRms(const AnyModel& model, const Rigid3d& mirror_from_board,
                            const std::vector<Vec3d>& board_points, const std::vector<Vec2d>& pixels) {
  double s = 0;
  int n = 0;
  for (size_t i = 0; i < board_points.size(); ++i) {
    Vec2d uv;
    if (!model.ImgFromPointUnbounded(mirror_from_board * board_points[i], &uv)) continue;
    s += (uv - pixels[i]).squaredNorm(), ++n;
  }
  return n ? std::sqrt(s / n) : HUGE_VAL;
}

bool FitBoardPose(const AnyModel& model, const std::vector<Vec3d>& board_points, const std::vector<Vec2d>& pixels,
                  Rigid3d* mirror_from_board, double* rms_px) {
  std::vector<Vec3d> bearings, pts;
  std::vector<Vec2d> obs;
  for (size_t i = 0; i < board_points.size() && i < pixels.size(); ++i) {
    Vec3d b;
    if (!model.MirrorFromImg(pixels[i], &b)) continue;
    bearings.push_back(b.normalized()), pts.push_back(board_points[i]), obs.push_back(pixels[i]);
  }
  if (bearings.size() < 4) return false;
  // A virtual pinhole looking along the mean bearing: PnP on the bearings' normalised coordinates.
  Vec3d z = Vec3d::Zero();
  for (const auto& b : bearings) z += b;
  z.normalize();
  const Vec3d x = (std::abs(z.z()) < 0.9 ? Vec3d::UnitZ() : Vec3d::UnitX()).cross(z).normalized();
  const Vec3d y = z.cross(x);
  Mat3<double> R;
  R.col(0) = x, R.col(1) = y, R.col(2) = z;  // mirror_from_virtual
  std::vector<cv::Point3f> op;
  std::vector<cv::Point2f> ip;
  for (size_t i = 0; i < bearings.size(); ++i) {
    const Vec3d v = R.transpose() * bearings[i];
    if (v.z() <= 0.05) continue;
    op.emplace_back(float(pts[i].x()), float(pts[i].y()), float(pts[i].z()));
    ip.emplace_back(float(v.x() / v.z()), float(v.y() / v.z()));
  }
  if (op.size() < 4) return false;
  cv::Mat rvec, tvec;
  if (!cv::solvePnP(op, ip, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_SQPNP))
    return false;
  const Vec3d aa(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  const Rigid3d virtual_from_board(QuaternionFromAngleAxis<double>(aa),
                                   Vec3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  const Rigid3d pose = Rigid3d(Eigen::Quaterniond(R), Vec3d::Zero()) * virtual_from_board;
  // Refinement through the model (pixel residuals).
  const Eigen::Quaterniond q0 = pose.rotation.normalized();
  double q[4] = {q0.x(), q0.y(), q0.z(), q0.w()},
         t[3] = {pose.translation(0), pose.translation(1), pose.translation(2)};
  ceres::Problem problem;
  for (size_t i = 0; i < pts.size(); ++i)
    problem.AddResidualBlock(
        new ceres::NumericDiffCostFunction<PointCost, ceres::CENTRAL, 2, 4, 3>(new PointCost{&model, pts[i], obs[i]}),
        new ceres::HuberLoss(1.0), q, t);
  problem.SetManifold(q, new ceres::EigenQuaternionManifold);
  ceres::Solver::Options so;
  so.max_num_iterations = 100;
  so.linear_solver_type = ceres::DENSE_QR;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE) return false;
  *mirror_from_board = ToPose(q, t);
  if (rms_px) *rms_px = BoardReprojectionRms(model, *mirror_from_board, board_points, pixels);
  return true;
}

}  // namespace hovs::calib
