// Visual positioning of the mirror over the camera (the article's rig sets the mirror with a turret and a
// height rod): the mirror's rim, seen directly by the camera as the outer edge of the mirror image, is found in
// one image and the camera centre's position relative to the nominal design is estimated from it.
//
// Detection: along `rays` half-lines from the nominal rim image centre, the strongest intensity step within
// search_px of the nominal rim radius (sub-pixel: a parabola through the gradient peak); rays without a step of
// min_step grey levels are skipped (a board or a bright object in front of the rim).
//
// Estimation: the rim is the circle of radius R at z = RimZ (mirror frame). Each edge pixel's camera ray must
// meet that plane at distance R from the axis; the camera centre's offset from the second focus (x, y lateral,
// z along the axis, + towards the mirror) is fitted with the camera's orientation held at the nominal one
// (Ceres, residuals in pixels). A small camera tilt and a lateral offset move the rim image almost alike (a tilt
// theta looks like an offset of about (RimZ - C_z) tan(theta)), so the lateral result is reported both ways;
// the height is independent of the tilt to first order. Where the reflection at the rim leaves upwards (a camera
// closer than the focus or to the side lifts the field's top above the rim plane there), the mount ring hides the
// last reflected pixels and the visible edge lies inside the rim: those edge points are left out (this was a
// 0.13 mm error in height with the camera 1 mm closer and 1.5 mm to the side, were they kept).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/catadioptric.h"

namespace hovs::calib {

struct RimEdgeOptions {
  int rays = 360;
  double search_px = 40;  // around the nominal rim radius
  double min_step = 20;   // grey levels across the edge (8-bit)
  void Check(const std::string& where) const;
};

struct RimEdge {
  std::vector<Vec2d> points;
  int rays = 0;  // searched
};

// grey: 8-bit, width x height of the nominal camera. Throws hovs::Error on a size mismatch.
RimEdge DetectRimEdge(const uint8_t* grey, int width, int height, const CatadioptricCamera<double>& nominal,
                      const RimEdgeOptions& options);

struct MirrorPosition {
  Vec3d offset = Vec3d::Zero();               // camera centre minus its nominal place (second focus), mirror frame, m
  Vec2d equivalent_tilt_rad = Vec2d::Zero();  // the lateral offset read as a camera tilt instead (about y, x)
  double rms_px = 0;
  int points = 0;
  Vec2d rim_centre_px = Vec2d::Zero(), nominal_rim_centre_px = Vec2d::Zero();
  double rim_radius_px = 0, nominal_rim_radius_px = 0;  // circle fits to the detected and the nominal rim
  bool converged = false;
  // Confidence: the edge points within kRimInlierPx of the fitted rim, as a count and a fraction of the points.
  int inliers = 0;
  double inlier_fraction = 0;
  // Edge points dropped because the mount ring hides the reflection next to the rim there (ReflectionMeetsMount).
  int occluded = 0;
};

// True when the camera ray through `pixel` (near the rim image) meets the rim where the reflection leaves less
// than kRimClearanceDeg below the rim plane: the mount ring around the rim then hides what the mirror shows just
// inside the rim, so the image's edge there is not the rim's (it lies up to a few pixels inside).
inline constexpr double kRimClearanceDeg = 0.1;
bool ReflectionMeetsMount(const CatadioptricCamera<double>& rig, const Vec2d& pixel);

// A rim is accepted when at least kRimMinInlierFraction of its edge points, and of the rays searched at least
// kRimMinRayFraction, lie within kRimInlierPx of the fitted rim: a real rim is one sharp edge on one curve (0.1 px
// RMS on renders), noise or clutter gives steps scattered over the whole search band.
inline constexpr double kRimInlierPx = 1.0;
inline constexpr double kRimMinInlierFraction = 0.6;
inline constexpr double kRimMinRayFraction = 0.25;

// Throws hovs::Error with fewer than 20 edge points.
MirrorPosition EstimateMirrorPosition(const RimEdge& edge, const CatadioptricCamera<double>& nominal);

// The nominal rig with its camera centre moved by `offset` (orientation unchanged).
CatadioptricCamera<double> WithCameraOffset(const CatadioptricCamera<double>& nominal, const Vec3d& offset);

// Detection and estimation, twice: the second pass searches +-search_px / 4 around the rim predicted from the
// first estimate (rays then cross the true edge near its normal, and a far-off nominal cannot pull in another
// edge). `edge` (optional) receives the second pass's points. Throws hovs::Error(where) when the rim fails the
// confidence test above (an image of noise, a rim out of view).
MirrorPosition LocateMirror(const uint8_t* grey, int width, int height, const CatadioptricCamera<double>& nominal,
                            const RimEdgeOptions& options, RimEdge* edge = nullptr,
                            const std::string& where = "mirror positioning");

}  // namespace hovs::calib
