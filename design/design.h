// The mirror design study of the article (section 3.1), done with the core's exact model.
//
// For a hyperboloid (a, b, rim diameter d) seen by a camera at its second focus:
//   upper bound of the vertical field   atan2(z_rim, d / 2)                   (ray from F1 through the rim)
//   lower bound                         atan2(-2c, d_lens / 2)                (ray from F1 to the lens rim)
//   vertical field                      upper - lower
//   rim image radius                    |pixel of the rim point - principal point|   (core projection)
//   mirror sag                          z_rim - z_vertex
//   system length                       2c (viewpoint to pinhole)
//   ground radii (mounting height h)    h / tan(-lower) .. h / tan(-upper)   (infinite if upper >= 0)
//   radial resolution                   d(rho) / d(elevation), px per degree, through ceres::Jet
//   resolution at the field's top       the radial resolution at the rim ray (the elevation nearest the horizon)
//   long-range resolution               the radial resolution at long_range_elevation_deg
//   near-ground coverage                image area (Mpx) of the ground disc of radius near_ground_radius around
//                                       the unit, outside the camera's own reflection
//   plate height (rod position)         z_rim + 2c: the rim plane (mounting plate) above the pinhole
// Constraints are written g <= 0 (feasible) in natural units (degrees, pixels, metres):
//   upper_bound_below_limit        upper - max_upper_elevation_deg           (the article: below the horizon)
//   rim_inside_image               rim radius - (min(W, H) / 2 - margin)     (the whole rim on the sensor, which
//                                                                             is also "the camera sees the mirror")
//   camera_reflection_inside_rim   camera reflection radius - rim radius     (the lower bound point is imaged)
//   optional: min_vertical_field, min_rim_radius, max_system_length,
//             rod_travel_min / rod_travel_max  (the plate height the push rod can reach)
//   long_range_elevation_in_field       long_range_elevation_deg - upper  (objective long_range_resolution only)
//   near_ground_disc_in_field           ground ring's elevation - upper    (objective near_ground_coverage only:
//                                                                             the whole near disc is seen)
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/catadioptric.h"
#include "core/lens.h"

namespace hovs::design {

struct CameraSpec {
  double focal_length = 0.016;   // m
  double pixel_pitch = 4.54e-6;  // m
  int width = 2750, height = 2200;
  double lens_aperture = 0.020;  // m, diameter of the lens (occludes the image centre)
  ThinLens lens;                 // f-number, focus in force, wavelength (its focal length: Lens())

  ThinLens Lens() const {
    ThinLens l = lens;
    l.focal_length = focal_length;
    return l;
  }
  // The projection at the focus in force: image scale s / pitch with s = f d_f / (d_f - f) (core/lens.h).
  PinholeCamera<double> Pinhole() const { return Lens().Camera(pixel_pitch, width, height); }
  void Check(const std::string& where) const;
};

// What the blur figures of a design cover (optics/README.md): the RMS radius a field point may have to count as
// sharp (the depth of field's limit), and the scene distances from F1 the worst blur and the best single focus
// are taken over.
struct BlurSpec {
  double limit_px = 1.0;
  double near = 1.0, far = HUGE_VAL;  // m from F1
  // constraints.max_blur_px: the chosen design's worst RMS radius over its field and [near, far] at its focus
  // (checked on the chosen design after the geometric search: each evaluation traces the blur atlas).
  std::optional<double> max_rms_px;
  // lens.f_number: auto: the f-number is a design variable, the widest aperture (most light) whose worst RMS
  // radius meets max_rms_px (else limit_px).
  bool auto_f_number = false;
  double FNumberLimitPx() const { return max_rms_px ? *max_rms_px : limit_px; }
  void Check(const std::string& where) const;
};

enum class Objective { kSmallestSystem, kWidestField, kLargestRim, kLongRange, kNearGround };
const char* ToString(Objective o);
std::optional<Objective> ObjectiveFromString(const std::string& s);

struct Range {
  double min = 0, max = 0;
  bool Fixed() const { return min == max; }
};

struct Constraints {
  double max_upper_elevation_deg = 0.0;  // upper bound of the field stays below this
  double rim_margin_px = 0.0;            // rim radius <= min(W, H) / 2 - margin
  std::optional<double> min_vertical_field_deg;
  std::optional<double> min_rim_radius_px;
  std::optional<double> max_system_length;  // m
  std::optional<Range> rod_travel;          // m, plate height (z_rim + 2c) the rod can set
};

struct DesignProblem {
  CameraSpec camera;
  double mounting_height = 1.3;            // m, viewpoint above the ground
  double long_range_elevation_deg = -5.0;  // where long_range_resolution is measured
  double near_ground_radius = 3.0;         // m, the ground disc near_ground_coverage counts
  Constraints constraints;
  BlurSpec blur;
  Objective objective = Objective::kSmallestSystem;
  Range a{0.020, 0.080}, b{0.020, 0.080}, d{0.080, 0.080};  // search box, m

  void Check(const std::string& where) const;
  double RimLimitPx() const;
  double NearGroundElevationDeg() const;  // elevation of the ground ring at near_ground_radius
};

struct DesignPoint {
  double a = 0, b = 0, d = 0;
};

struct Metrics {
  DesignPoint p;
  double c = 0, system_length = 0, rim_z = 0, vertex_z = 0, sag = 0;
  double upper_deg = 0, lower_deg = 0, field_deg = 0;
  double rim_radius_px = 0, reflection_radius_px = 0;
  double ground_radius_inner = 0, ground_radius_outer = 0;  // m; outer is +inf when upper >= 0
  double plate_height = 0;                                  // m, rim plane above the pinhole (rod position)
  double upper_px_per_deg = 0;                              // radial resolution at the rim ray
  double long_range_px_per_deg = 0;                         // at long_range_elevation_deg (0 outside the field)
  double near_ground_mpx = 0;                               // image area of the near ground disc, Mpx
};

struct ConstraintValue {
  std::string name;
  double value = 0;  // g <= 0 is feasible
  double limit = 0;
  std::string unit;
};

// The aligned rig of a design (pinhole at F2, occluder = lens aperture).
CatadioptricCamera<double> RigOf(const DesignPoint& p, const CameraSpec& camera);

Metrics Evaluate(const DesignPoint& p, const DesignProblem& problem);
std::vector<ConstraintValue> EvaluateConstraints(const Metrics& m, const DesignProblem& problem);
double MaxViolation(const std::vector<ConstraintValue>& g);
// The objective as a value to minimise: 2c (m), -field (deg), -rim radius (px), -long-range resolution
// (px / deg), -near-ground coverage (Mpx).
double ObjectiveValue(const Metrics& m, Objective o);

struct ResolutionSample {
  double elevation_deg, rho_px, px_per_deg;
};
// Radial resolution over the vertical field (n samples strictly inside it).
std::vector<ResolutionSample> RadialResolution(const DesignPoint& p, const CameraSpec& camera, int n);

// ---- Sweep -------------------------------------------------------------------------------------------
struct SweepSpec {
  int na = 400, nb = 400, nd = 1;
  void Check(const std::string& where) const;
};

struct SweepResult {
  SweepSpec spec;
  Range a, b, d;
  std::vector<std::string> constraint_names;
  // Arrays of na * nb * nd, index ((id * nb) + ib) * na + ia.
  std::vector<double> upper_deg, lower_deg, field_deg, rim_px, system_length, objective;
  std::vector<uint32_t> violated;  // bit k set: constraint k violated
  double A(int ia) const { return spec.na == 1 ? a.min : a.min + (a.max - a.min) * ia / (spec.na - 1); }
  double B(int ib) const { return spec.nb == 1 ? b.min : b.min + (b.max - b.min) * ib / (spec.nb - 1); }
  double D(int id) const { return spec.nd == 1 ? d.min : d.min + (d.max - d.min) * id / (spec.nd - 1); }
  size_t Index(int ia, int ib, int id) const { return (static_cast<size_t>(id) * spec.nb + ib) * spec.na + ia; }
  size_t size() const { return objective.size(); }
  // Best feasible point by objective (none if the grid has no feasible point).
  std::optional<size_t> BestFeasible() const;
};

SweepResult Sweep(const DesignProblem& problem, const SweepSpec& spec);
// Rows [row_first, row_end) of the sweep (row ib + nb * id holds the na designs of that b and d), the other rows'
// values left zero: one shard of the grid (hovs design --shard). Sweep is every row.
SweepResult SweepRows(const DesignProblem& problem, const SweepSpec& spec, size_t row_first, size_t row_end);

// ---- Optimum -----------------------------------------------------------------------------------------
struct Optimum {
  Metrics metrics;
  std::vector<ConstraintValue> constraints;
  double objective = 0;
  double max_violation = 0;
  std::string method;  // which solver produced it, and whether it was repaired
  int evaluations = 0;
  std::vector<std::string> solver_log;  // one line per solver run
};

// Constrained optimum with NLopt (COBYLA, then SLSQP with Jet gradients, from the best feasible sweep point),
// verified feasible after the solvers return. Throws hovs::Error when no feasible design exists.
Optimum OptimizeContinuous(const DesignProblem& problem, const SweepResult& sweep);

// Best design on an integer-millimetre grid of (a, b) (and d when it is free). None if none is feasible.
std::optional<Optimum> OptimizeIntegerMillimetre(const DesignProblem& problem);

}  // namespace hovs::design
