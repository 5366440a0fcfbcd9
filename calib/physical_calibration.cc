#include "calib/physical_calibration.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "calib/solver_util.h"
#include "core/error.h"

#include <cstdio>
#include <cstdlib>
#include <map>

namespace hovs::calib {
namespace {

struct PhysicalReprojection {
  PhysicalReprojection(const Vec3d& P, const Vec2d& obs, const CatadioptricCamera<double>* nominal)
      : P_(P), obs_(obs), nominal_(nominal) {}
  // Blocks: mirror [a, b], intrinsics [fx, fy, cx, cy], distortion [k1, k2, p1, p2], misalignment
  // [tilt (3), offset (3)], board pose [angle-axis (3), t (3)].
  template <class T>
  bool operator()(const T* mirror, const T* intr, const T* dist, const T* mis, const T* pose, T* residual) const {
    // Every observed corner is seen by definition: project without the visibility limits (rim, camera body,
    // sensor bounds), so a start slightly off does not reject corners near the rim.
    CatadioptricCamera<T> rig = nominal_->Cast<T>().Unbounded();
    rig.mirror.a = mirror[0], rig.mirror.b = mirror[1];
    rig.camera.fx = intr[0], rig.camera.fy = intr[1], rig.camera.cx = intr[2], rig.camera.cy = intr[3];
    rig.camera.distortion = {dist[0], dist[1], dist[2], dist[3]};
    rig.cam_from_mirror =
        CamFromMirrorMisaligned<T>(rig.mirror, Vec3<T>(mis[0], mis[1], mis[2]), Vec3<T>(mis[3], mis[4], mis[5]));
    const T Pb[3] = {T(P_.x()), T(P_.y()), T(P_.z())};
    T X[3];
    ceres::AngleAxisRotatePoint(pose, Pb, X);
    Vec2<T> uv;
    if (rig.ImgFromMirrorGeneral(Vec3<T>(X[0] + pose[3], X[1] + pose[4], X[2] + pose[5]), &uv) != ProjectionStatus::kOk)
      return false;
    residual[0] = uv(0) - T(obs_.x());
    residual[1] = uv(1) - T(obs_.y());
    return true;
  }
  Vec3d P_;
  Vec2d obs_;
  const CatadioptricCamera<double>* nominal_;
};

// A rim edge pixel: its camera ray must meet the rim plane (z = RimZ, mirror frame) at the rim radius.
// Same blocks as PhysicalReprojection but the board pose; residual in pixels (radial miss x f / depth).
struct RimRayResidual {
  RimRayResidual(const Vec2d& px, const CatadioptricCamera<double>* nominal) : px_(px), nominal_(nominal) {}
  template <class T>
  bool operator()(const T* mirror, const T* intr, const T* dist, const T* mis, T* residual) const {
    CatadioptricCamera<T> rig = nominal_->Cast<T>();
    rig.mirror.a = mirror[0], rig.mirror.b = mirror[1];
    rig.camera.fx = intr[0], rig.camera.fy = intr[1], rig.camera.cx = intr[2], rig.camera.cy = intr[3];
    rig.camera.distortion = {dist[0], dist[1], dist[2], dist[3]};
    rig.cam_from_mirror =
        CamFromMirrorMisaligned<T>(rig.mirror, Vec3<T>(mis[0], mis[1], mis[2]), Vec3<T>(mis[3], mis[4], mis[5]));
    Vec3<T> ray;
    if (!rig.camera.CamFromImg(Vec2<T>(T(px_.x()), T(px_.y())), &ray)) return false;
    const Rigid3<T> mirror_from_cam = rig.cam_from_mirror.Inverse();
    const Vec3<T> C = mirror_from_cam.translation, d = mirror_from_cam.rotation * ray;
    const T z = rig.mirror.RimZ();
    if (!(ScalarPart(d(2)) > 1e-9)) return false;
    const T t = (z - C(2)) / d(2);
    const Vec3<T> X = C + t * d;
    using std::sqrt;
    residual[0] = (sqrt(X(0) * X(0) + X(1) * X(1)) - rig.mirror.RimRadius()) * rig.camera.fx / (z - C(2));
    return true;
  }
  Vec2d px_;
  const CatadioptricCamera<double>* nominal_;
};

}  // namespace

PhysicalCalibration CalibratePhysical(const std::vector<BoardObservation>& obs,
                                      const CatadioptricCamera<double>& nominal, const PolynomialCalibration& start,
                                      const PhysicalCalibrationOptions& opt) {
  nominal.Check("physical calibration (nominal rig)");
  HOVS_REQUIRE(obs.size() >= 3 && start.cam_from_board.size() == obs.size(), "physical calibration",
               "needs at least three images and a start with their poses");
  double mirror[2] = {nominal.mirror.a, nominal.mirror.b};
  double intr[4] = {nominal.camera.fx, nominal.camera.fy, nominal.camera.cx, nominal.camera.cy};
  double dist[4] = {nominal.camera.distortion.k1, nominal.camera.distortion.k2, nominal.camera.distortion.p1,
                    nominal.camera.distortion.p2};
  double mis[6] = {0, 0, 0, 0, 0, 0};
  std::vector<std::array<double, 6>> poses(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) poses[i] = PoseToParams(start.cam_from_board[i]);
  ceres::Problem problem;
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t j = 0; j < obs[i].pixels.size(); ++j)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PhysicalReprojection, 2, 2, 4, 4, 6, 6>(
                                   new PhysicalReprojection(obs[i].board_points[j], obs[i].pixels[j], &nominal)),
                               nullptr, mirror, intr, dist, mis, poses[i].data());
  for (const Vec2d& p : opt.rim_points)
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<RimRayResidual, 1, 2, 4, 4, 6>(new RimRayResidual(p, &nominal)),
        new ceres::HuberLoss(1.0), mirror, intr, dist, mis);
  if (!opt.estimate_distortion) problem.SetParameterBlockConstant(dist);
  if (!opt.estimate_intrinsics) problem.SetParameterBlockConstant(intr);
  // The mirror is symmetric about its axis: turning the camera about that axis is absorbed by the board poses.
  // Hold that component of the tilt at zero (the gauge).
  problem.SetManifold(mis, new ceres::SubsetManifold(6, {2}));
  if (!opt.estimate_mirror) problem.SetParameterBlockConstant(mirror);
  for (int k = 0; k < 2; ++k) problem.SetParameterLowerBound(mirror, k, 1e-4);
  const ceres::Solver::Options so = CalibrationSolverOptions(opt.max_iterations, 1e-15);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  PhysicalCalibration out;
  out.converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  out.solver_report = summary.BriefReport();
  out.rig = nominal;
  out.rig.mirror.a = mirror[0], out.rig.mirror.b = mirror[1];
  out.rig.camera.fx = intr[0], out.rig.camera.fy = intr[1], out.rig.camera.cx = intr[2], out.rig.camera.cy = intr[3];
  out.rig.camera.distortion = {dist[0], dist[1], dist[2], dist[3]};
  out.tilt = Vec3d(mis[0], mis[1], mis[2]);
  out.offset = Vec3d(mis[3], mis[4], mis[5]);
  out.rig.cam_from_mirror = CamFromMirrorMisaligned<double>(out.rig.mirror, out.tilt, out.offset);
  // The RMS with the same projection as the residuals (no visibility limits).
  CatadioptricCamera<double> unlimited = out.rig;
  unlimited.mirror.rim_diameter *= 3;
  unlimited.occluder_radius = 0;
  unlimited.camera.width = unlimited.camera.height = 0;
  double sum2 = 0;
  size_t n = 0;
  for (size_t i = 0; i < obs.size(); ++i) {
    out.mirror_from_board.push_back(ParamsToPose(poses[i].data()));
    for (size_t j = 0; j < obs[i].pixels.size(); ++j, ++n) {
      Vec2d uv;
      sum2 += unlimited.ImgFromMirrorGeneral(out.mirror_from_board[i] * obs[i].board_points[j], &uv) ==
                      ProjectionStatus::kOk
                  ? (uv - obs[i].pixels[j]).squaredNorm()
                  : 1e12;
    }
  }
  out.rms = std::sqrt(sum2 / n);
  if (!opt.rim_points.empty()) {
    double r2 = 0;
    for (const Vec2d& p : opt.rim_points) {
      double r = 0;
      const double m[2] = {mirror[0], mirror[1]};
      RimRayResidual(p, &nominal)(m, intr, dist, mis, &r);
      r2 += r * r;
    }
    out.rim_rms = std::sqrt(r2 / opt.rim_points.size());
  }
  return out;
}

}  // namespace hovs::calib
