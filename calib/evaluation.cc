#include "calib/evaluation.h"

#include <algorithm>
#include <utility>

#include "core/statistics.h"

namespace hovs::calib {
namespace {

int GridStep(int width, const RayAccuracyOptions& o) { return std::max(o.min_step, width / o.columns); }

}  // namespace

RayAccuracy CompareWithTruth(const CatadioptricCamera<double>& truth, const PolynomialModel<double>& model,
                             const RayAccuracyOptions& options) {
  const int width = truth.camera.width, height = truth.camera.height, step = GridStep(width, options);
  RunningStats raw;
  std::vector<std::pair<Vec3d, Vec3d>> rays;  // (true, model)
  for (int v = 0; v < height; v += step)
    for (int u = 0; u < width; u += step) {
      const Vec2d uv(u, v);
      const double rho = model.RhoOfImg(uv);
      if (!truth.SeesMirror(uv) || rho < model.rho_min || rho > model.rho_max) continue;
      Vec3d M, d, b;
      if (!truth.RayFromImg(uv, &M, &d) || !model.CamFromImg(uv, &b)) continue;
      const Vec3d a = (M + options.distance * d).normalized();
      raw.Add(AngleBetweenDeg(a, b));
      rays.emplace_back(a.normalized(), b.normalized());
    }
  RayAccuracy r;
  r.pixels = static_cast<int>(raw.count);
  if (rays.empty()) return r;
  const Mat3<double> R = BestRotation(rays);  // a ~ R b
  RunningStats aligned;
  for (const auto& [a, b] : rays) aligned.Add(AngleBetweenDeg(a, R * b));
  r.mean_deg = raw.Mean(), r.max_deg = raw.max;
  r.mean_aligned_deg = aligned.Mean(), r.max_aligned_deg = aligned.max;
  r.frame_rotation_deg = Eigen::AngleAxisd(R).angle() * 180 / M_PI;
  return r;
}

PhysicalAccuracy CompareWithTruth(const CatadioptricCamera<double>& truth, const CatadioptricCamera<double>& calibrated,
                                  const RayAccuracyOptions& options) {
  const int width = truth.camera.width, height = truth.camera.height, step = GridStep(width, options);
  RunningStats s;
  for (int v = 0; v < height; v += step)
    for (int u = 0; u < width; u += step) {
      const Vec2d uv(u, v);
      Vec3d M, d, Mc, dc;
      if (!truth.SeesMirror(uv) || !truth.RayFromImg(uv, &M, &d) || !calibrated.RayFromImg(uv, &Mc, &dc)) continue;
      s.Add(AngleBetweenDeg((M + options.distance * d).normalized(), (Mc + options.distance * dc).normalized()));
    }
  PhysicalAccuracy r;
  r.pixels = static_cast<int>(s.count);
  r.mean_deg = s.Mean(), r.max_deg = s.max;
  const Eigen::Quaterniond dq = truth.cam_from_mirror.rotation * calibrated.cam_from_mirror.rotation.conjugate();
  r.tilt_error_deg = 2 * std::asin(std::min(1.0, dq.vec().norm())) * 180 / M_PI;
  r.centre_error_m = (truth.CameraCentre() - calibrated.CameraCentre()).norm();
  return r;
}

CornerAccuracy CompareWithTruth(const std::vector<Vec2d>& detected, const std::vector<Vec2d>& truth) {
  CornerAccuracy r;
  if (detected.empty() || truth.empty()) return r;
  double ss = 0;
  for (const auto& p : detected) {
    double best = 1e30;
    for (const auto& t : truth) best = std::min(best, (t - p).norm());
    ss += best * best, r.max_px = std::max(r.max_px, best);
  }
  r.rms_px = std::sqrt(ss / detected.size());
  return r;
}

}  // namespace hovs::calib
