// Synthetic board observations for calibration tests and benchmarks.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "calib/polynomial_calibration.h"
#include "core/catadioptric.h"

namespace hovs::calib {

// Rotation of a board centred at c whose z axis points at the viewpoint (the origin), x horizontal.
inline Mat3<double> FacingViewpoint(const Vec3d& c) {
  const Vec3d z = -c.normalized();
  const Vec3d x = Vec3d(0, 0, 1).cross(z).normalized(), y = z.cross(x);
  Mat3<double> R;
  R.col(0) = x, R.col(1) = y, R.col(2) = z;
  return R;
}

// The article's board (7 x 5 inner corners, 30 mm) at random poses around the reference unit, projected by the
// core's exact model; every corner visible.
inline std::vector<BoardObservation> SyntheticObservations(const CatadioptricCamera<double>& rig, int images,
                                                           double noise_px, unsigned seed,
                                                           std::vector<Rigid3d>* poses = nullptr) {
  constexpr double kDeg = M_PI / 180;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, noise_px);
  std::vector<BoardObservation> out;
  while (static_cast<int>(out.size()) < images) {
    const double az = U(rng) * 2 * M_PI, el = (-50 + 38 * U(rng)) * kDeg, dist = 0.3 + 0.3 * U(rng);
    const Vec3d c = dist * Vec3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    // Board facing the viewpoint, tilted a little, rolled.
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(FacingViewpoint(c)) *
        Eigen::Quaterniond(Eigen::AngleAxisd((U(rng) - 0.5) * 0.6, Vec3d(U(rng), U(rng), 0).normalized())) *
        Eigen::Quaterniond(Eigen::AngleAxisd(U(rng) * 2 * M_PI, Vec3d::UnitZ()));
    const Rigid3d mirror_from_board(q, c);
    BoardObservation o;
    o.image = "synthetic" + std::to_string(out.size());
    bool ok = true;
    for (int j = 1; j < 6 && ok; ++j)
      for (int i = 1; i < 8 && ok; ++i) {
        const Vec3d P((i - 4) * 0.03, (j - 3) * 0.03, 0);
        Vec2d uv;
        ok = rig.ImgFromMirror(mirror_from_board * P, &uv) == ProjectionStatus::kOk;
        o.board_points.push_back(P);
        o.pixels.push_back(uv + Vec2d(N(rng), N(rng)));
      }
    if (!ok) continue;
    out.push_back(o);
    if (poses) poses->push_back(mirror_from_board);
  }
  return out;
}

// A cols x rows-corner board (square in metres) at random poses around the viewpoint (centre elevation in
// [el_lo, el_hi] degrees, distance in [d_lo, d_hi] m), projected by any model's ImgFromCam; an image is kept
// when every corner lands inside width x height. `poses`: the kept boards' cam_from_board.
template <class Model>
std::vector<BoardObservation> SyntheticBoardsThrough(const Model& model, int width, int height, int cols, int rows,
                                                     double square, int images, double noise_px, unsigned seed,
                                                     double el_lo, double el_hi, double d_lo, double d_hi,
                                                     std::vector<Rigid3d>* poses = nullptr) {
  constexpr double kDeg = M_PI / 180;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, noise_px);
  std::vector<BoardObservation> out;
  for (int tries = 0; static_cast<int>(out.size()) < images && tries < 100000; ++tries) {
    const double az = U(rng) * 2 * M_PI, el = (el_lo + (el_hi - el_lo) * U(rng)) * kDeg;
    const double dist = d_lo + (d_hi - d_lo) * U(rng);
    const Vec3d c = dist * Vec3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(FacingViewpoint(c)) *
        Eigen::Quaterniond(Eigen::AngleAxisd((U(rng) - 0.5) * 0.8, Vec3d(U(rng), U(rng), 0).normalized())) *
        Eigen::Quaterniond(Eigen::AngleAxisd(U(rng) * 2 * M_PI, Vec3d::UnitZ()));
    const Rigid3d cam_from_board(q, c);
    BoardObservation o;
    o.image = "synthetic" + std::to_string(out.size());
    bool ok = true;
    for (int j = 0; j < rows && ok; ++j)
      for (int i = 0; i < cols && ok; ++i) {
        const Vec3d P((i - 0.5 * (cols - 1)) * square, (j - 0.5 * (rows - 1)) * square, 0);
        Vec2d uv;
        ok = model.ImgFromCam(cam_from_board * P, &uv) && uv.x() >= 0 && uv.y() >= 0 && uv.x() <= width - 1 &&
             uv.y() <= height - 1;
        o.board_points.push_back(P);
        o.pixels.push_back(uv + Vec2d(N(rng), N(rng)));
      }
    if (!ok) continue;
    out.push_back(o);
    if (poses) poses->push_back(cam_from_board);
  }
  return out;
}

}  // namespace hovs::calib
