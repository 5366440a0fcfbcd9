// The blur of a catadioptric design: exact spot diagrams, through-focus, depth of field and MTF of field points
// (definitions in optics/README.md).
//
// A field point X (mirror frame) is imaged by tracing a bundle from X via the exact mirror into the lens pupil:
// for each pupil point L (a disc of the aperture radius in the lens plane, sampled uniformly by area), the
// mirror point M where X reflects into L (law of reflection solved per L, core/catadioptric.h), then the ray
// M -> L through the thin lens to the sensor. With the lens focused at d (object side, along the optical axis)
// the ray that enters the lens at L with direction w (camera frame, towards the scene) meets the plane in focus
// at P = L + w d / w_z, and the sensor at the pinhole projection of P:
//   u = cx + fx (L_x / d + w_x / w_z),  v = cy + fy (L_y / d + w_y / w_z),   fx = fy = s(d) / pitch
// (the renderer's thin lens; raytrace/camera_rays.cc). A bundle is traced once and refocused analytically.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/catadioptric.h"
#include "core/lens.h"

namespace hovs::optics {

// Where a point "at infinity" is traced (m from F1): its bundle differs from the limit by far less than 1e-6 px.
inline constexpr double kFarDistance = 1e7;

// A point of the scene by elevation (deg, from the plane z = 0 of the mirror frame), azimuth (deg, about z from
// +x) and distance (m) from the viewpoint F1.
struct FieldPoint {
  double elevation_deg = 0, azimuth_deg = 0, distance = 1;
  Vec3d Position() const;
};

// The rays of a field point's bundle that reach the lens, in the camera frame: pupil point (lx, ly) on the lens
// plane (m) and the slopes (tx, ty) = (w_x / w_z, w_y / w_z) of the ray towards the scene.
struct Bundle {
  std::vector<double> lx, ly, tx, ty;
  int pupil_samples = 0;  // pupil points tried
  int lost = 0;           // of those, with no mirror point within the rim (vignetted by the rim, or no solution)
  bool Empty() const { return lx.empty(); }
  size_t size() const { return lx.size(); }
};

// n pupil points uniform by area on the disc of radius r (a Vogel spiral: point k at radius r sqrt((k + 0.5) / n),
// angle k times the golden angle). Interleaved x, y.
std::vector<double> PupilPoints(int n, double radius);

// The bundle of X (mirror frame) through the pupil of radius `aperture_radius` about the rig's camera centre in
// its lens plane, with `pupil` the points of PupilPoints (metres). A pupil of radius 0 traces the chief ray alone.
Bundle TraceBundle(const CatadioptricCamera<double>& rig, const Vec3d& X, double aperture_radius,
                   const std::vector<double>& pupil);

// A spot on the sensor, pixels. Radial: along the direction from the principal point to the centroid;
// tangential: across it. ee80: the radius about the centroid that holds 80 % of the rays (nearest rank).
struct Spot {
  Vec2d centroid = Vec2d::Zero();
  double rms = 0, radial_rms = 0, tangential_rms = 0, ee80 = 0;
  Vec2d radial_dir = Vec2d(1, 0);
  std::vector<Vec2d> points;  // the rays' sensor points (kept when asked)
  int rays = 0;
  bool Valid() const { return rays > 0; }
};

// The spot of a bundle with the lens focused at focus_distance and the projection of `camera` (fx, fy: the
// image scale at that focus; cx, cy). keep_points: fill Spot::points.
Spot SpotAt(const Bundle& b, const PinholeCamera<double>& camera, double focus_distance, bool keep_points = false);

// Geometric MTF of a spot along a unit direction (pixels) at nu cycles / px: |mean exp(2 pi i nu (p - c) . dir)|.
double GeometricMtf(const Spot& s, const Vec2d& dir, double nu);
// The diffraction MTF of an aberration-free circular pupil at nu cycles / px, for a working f-number N_w:
// (2 / pi) (acos x - x sqrt(1 - x^2)), x = nu / nu_c, nu_c = pitch / (lambda N_w); 0 past the cut-off.
double DiffractionMtf(double nu, double pixel_pitch, double wavelength, double working_f_number);
// The pixel's own MTF (a square pixel of full fill factor, box-filtered): |sinc(nu)|.
double PixelMtf(double nu);
// The lowest frequency (cycles / px, within (0, nu_max]) where mtf(nu) falls to 0.5, linear between steps of
// nu_max / 400; nu_max when it never does.
double Mtf50(const std::function<double(double)>& mtf, double nu_max = 1.0);

// The MTF of a spot along a unit direction, geometric times the diffraction of the working f-number: its value
// at Nyquist (0.5 cycles / px) and its MTF50 (cycles / px, in (0, 1]; 1 when it stays above 0.5), on steps of
// 1 / 256 cycles / px (the geometric part by a rotation recurrence, exact to rounding), linear between steps.
struct MtfFigures {
  double nyquist = 0, mtf50 = 0;
};
MtfFigures MtfAlong(const Spot& s, const Vec2d& dir, double pixel_pitch, double wavelength, double working_f_number);

// Everything the optics of a design depend on: the rig (mirror, camera pose), the sensor and the lens.
struct OpticalSystem {
  CatadioptricCamera<double> rig;  // its camera's fx, fy are replaced by the lens's scale at each focus
  ThinLens lens;
  double pixel_pitch = 4.54e-6;
  int pupil_samples = 256;
  void Check(const std::string& where) const;
  PinholeCamera<double> CameraAt(double focus_distance) const;
};

// The blur figures of one field point at one focus (what blur.csv holds per row).
struct FieldBlur {
  FieldPoint field;
  double focus_distance = 0;
  Spot spot;
  double mtf_nyquist_radial = 0, mtf_nyquist_tangential = 0;  // geometric x diffraction, at 0.5 cycles / px
  double mtf50_radial = 0, mtf50_tangential = 0;              // cycles / px
  int rays = 0, lost = 0;
};

FieldBlur BlurOf(const OpticalSystem& sys, const FieldPoint& f, const Bundle& b, double focus_distance,
                 bool keep_points = false);
FieldBlur BlurOf(const OpticalSystem& sys, const FieldPoint& f, double focus_distance, bool keep_points = false);

}  // namespace hovs::optics
