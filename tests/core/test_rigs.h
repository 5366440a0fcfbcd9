// Realistic parameters shared by the core tests: the article's reference unit.
#pragma once

#include <cmath>
#include <random>

#include "core/catadioptric.h"

namespace hovs::test {

inline HyperboloidMirror<double> ReferenceMirror() { return {0.048, 0.044, 0.080}; }
inline PinholeCamera<double> ReferenceCamera() {
  return PinholeCamera<double>::FromPhysical(0.016, 4.54e-6, 2750, 2200);
}
inline CatadioptricCamera<double> AlignedRig() {
  return CatadioptricCamera<double>::Aligned(ReferenceMirror(), ReferenceCamera(), 0.010);
}
// A physically misaligned rig: the camera turned by about 1 degree about F1 and offset by about 1 mm.
inline CatadioptricCamera<double> MisalignedRig() {
  auto rig = AlignedRig();
  const double deg = M_PI / 180;
  const Rigid3d mirror_eps(QuaternionFromAngleAxis<double>(Vec3d(1.0 * deg, 0.4 * deg, 0.0)),
                           Vec3d(0.001, -0.0005, 0.001));
  rig.cam_from_mirror = rig.cam_from_mirror * mirror_eps;
  return rig;
}

// Pixels on a grid that see the mirror.
template <class Rig>
std::vector<Vec2d> MirrorPixels(const Rig& rig, int step) {
  std::vector<Vec2d> out;
  for (int v = 0; v < rig.camera.height; v += step)
    for (int u = 0; u < rig.camera.width; u += step) {
      const Vec2d uv(u + 0.25, v + 0.75);
      if (rig.SeesMirror(uv)) out.push_back(uv);
    }
  return out;
}

// World points around the unit (mirror frame), 0.5 .. 10 m away, elevations -60 .. -5 degrees.
inline std::vector<Vec3d> WorldPoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> az(-M_PI, M_PI), el(-60 * M_PI / 180, -5 * M_PI / 180), range(0.5, 10.0);
  std::vector<Vec3d> out;
  for (int i = 0; i < n; ++i) {
    const double a = az(rng), e = el(rng), r = range(rng);
    out.emplace_back(r * std::cos(e) * std::cos(a), r * std::cos(e) * std::sin(a), r * std::sin(e));
  }
  return out;
}

}  // namespace hovs::test
