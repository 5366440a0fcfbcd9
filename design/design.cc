#include "design/design.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <nlopt.hpp>

#include "core/error.h"
#include "core/model_fit.h"

namespace hovs::design {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The quantities the constraints and objectives need, in any scalar type (Jets give SLSQP its gradients).
// Everything goes through the core's mirror and camera models.
template <class T>
struct Geometry {
  T c, rim_z, upper, lower, rim_px, reflection_px;
  T upper_res, long_range_res, near_ground_mpx;  // px / deg, px / deg, Mpx
};

// Radial resolution (px per degree of elevation) at the sheet point of radius r, for a pinhole of focal length
// f px at F2 on the axis: rho(r) = f r / (z(r) + 2c) and elevation(r) = atan2(z(r), r), so
// d rho / d elevation = (d rho / dr) / (d elevation / dr). RadialResolution computes the same through the
// core's projection; a test keeps the two equal.
template <class T>
T ResolutionAtRadius(const HyperboloidMirror<T>& mirror, const T& f, const T& r) {
  using std::abs;
  const T z = mirror.SheetZ(r);
  const T dz = mirror.Slope(r, T(0))(0);
  const T depth = z + T(2) * mirror.c();
  const T drho = f * (depth - r * dz) / (depth * depth);
  const T delev = (r * dz - z) / (r * r + z * z);
  return abs(drho / delev) * T(kDeg);
}

template <class T>
Geometry<T> ComputeGeometry(const T& a, const T& b, const T& d, const CameraSpec& camera,
                            double long_range_elevation_deg = -5.0, double near_ground_radius = 3.0,
                            double mounting_height = 1.3) {
  using std::atan2;
  using std::sqrt;
  CatadioptricCamera<T> rig = CatadioptricCamera<T>::Aligned(
      HyperboloidMirror<T>{a, b, d}, camera.Pinhole().template Cast<T>(), T(0.5 * camera.lens_aperture));
  Geometry<T> g;
  g.c = rig.mirror.c();
  g.rim_z = rig.mirror.RimZ();
  g.upper = atan2(g.rim_z, rig.mirror.RimRadius());
  g.lower = atan2(T(-2) * g.c, rig.occluder_radius);
  // Image radius of a mirror point, through the core's camera model.
  const auto radius_px = [&](const Vec3<T>& M) {
    Vec2<T> uv;
    if (!rig.camera.ImgFromCam(rig.cam_from_mirror * M, &uv)) return T(std::numeric_limits<double>::infinity());
    return sqrt((uv(0) - rig.camera.cx) * (uv(0) - rig.camera.cx) + (uv(1) - rig.camera.cy) * (uv(1) - rig.camera.cy));
  };
  g.rim_px = radius_px(Vec3<T>(rig.mirror.RimRadius(), T(0), g.rim_z));
  // The camera's own reflection: the mirror point seen from F1 towards the lens rim.
  Vec3<T> M;
  g.reflection_px = rig.mirror.PointAlong(Vec3<T>(rig.occluder_radius, T(0), T(-2) * g.c), &M)
                        ? radius_px(M)
                        : T(std::numeric_limits<double>::infinity());
  const T f = rig.camera.fx;
  g.upper_res = ResolutionAtRadius(rig.mirror, f, rig.mirror.RimRadius());
  // The mirror point seen at a given elevation (its radius; may lie beyond the rim, where the sheet continues).
  const auto radius_at = [&](double elevation, T* r) {
    Vec3<T> P;
    if (!rig.mirror.PointAlong(Vec3<T>(T(std::cos(elevation)), T(0), T(std::sin(elevation))), &P)) return false;
    *r = P(0);
    return true;
  };
  T r;
  g.long_range_res = radius_at(long_range_elevation_deg * kDeg, &r) ? ResolutionAtRadius(rig.mirror, f, r) : T(0);
  // Near ground: the ground point at near_ground_radius is imaged at rho_g unless it lies beyond the field's
  // top, where the whole imaged ground is nearer (rho_g = rim).
  const double ground_elevation = -std::atan2(mounting_height, near_ground_radius);
  T rho_g = g.rim_px;
  if (ScalarPart(g.upper) > ground_elevation && radius_at(ground_elevation, &r))
    rho_g = radius_px(Vec3<T>(r, T(0), rig.mirror.SheetZ(r)));
  const T area = T(M_PI) * (rho_g * rho_g - g.reflection_px * g.reflection_px) * T(1e-6);
  g.near_ground_mpx = ScalarPart(area) > 0 ? area : T(0);
  return g;
}

template <class T>
Geometry<T> ComputeGeometry(const T& a, const T& b, const T& d, const DesignProblem& p) {
  return ComputeGeometry(a, b, d, p.camera, p.long_range_elevation_deg, p.near_ground_radius, p.mounting_height);
}

// Constraint k as g <= 0, in natural units, for any scalar type.
template <class T>
std::vector<T> ConstraintVector(const Geometry<T>& g, const DesignProblem& p) {
  std::vector<T> out;
  const Constraints& k = p.constraints;
  out.push_back(g.upper / T(kDeg) - T(k.max_upper_elevation_deg));
  out.push_back(g.rim_px - T(p.RimLimitPx()));
  out.push_back(g.reflection_px - g.rim_px);
  if (k.min_vertical_field_deg) out.push_back(T(*k.min_vertical_field_deg) - (g.upper - g.lower) / T(kDeg));
  if (k.min_rim_radius_px) out.push_back(T(*k.min_rim_radius_px) - g.rim_px);
  if (k.max_system_length) out.push_back(T(2) * g.c - T(*k.max_system_length));
  if (k.rod_travel) {
    const T plate = g.rim_z + T(2) * g.c;
    out.push_back(T(k.rod_travel->min) - plate);
    out.push_back(plate - T(k.rod_travel->max));
  }
  if (p.objective == Objective::kLongRange) out.push_back(T(p.long_range_elevation_deg) - g.upper / T(kDeg));
  if (p.objective == Objective::kNearGround) out.push_back(T(p.NearGroundElevationDeg()) - g.upper / T(kDeg));
  return out;
}

std::vector<ConstraintValue> DescribeConstraints(const std::vector<double>& v, const DesignProblem& p) {
  const Constraints& k = p.constraints;
  std::vector<ConstraintValue> out;
  size_t i = 0;
  out.push_back({"upper_bound_below_limit", v[i++], k.max_upper_elevation_deg, "deg"});
  out.push_back({"rim_inside_image", v[i++], p.RimLimitPx(), "px"});
  out.push_back({"camera_reflection_inside_rim", v[i++], 0.0, "px"});
  if (k.min_vertical_field_deg) out.push_back({"min_vertical_field", v[i++], *k.min_vertical_field_deg, "deg"});
  if (k.min_rim_radius_px) out.push_back({"min_rim_radius", v[i++], *k.min_rim_radius_px, "px"});
  if (k.max_system_length) out.push_back({"max_system_length", v[i++], *k.max_system_length, "m"});
  if (k.rod_travel) {
    out.push_back({"rod_travel_min", v[i++], k.rod_travel->min, "m"});
    out.push_back({"rod_travel_max", v[i++], k.rod_travel->max, "m"});
  }
  if (p.objective == Objective::kLongRange)
    out.push_back({"long_range_elevation_in_field", v[i++], p.long_range_elevation_deg, "deg"});
  if (p.objective == Objective::kNearGround)
    out.push_back({"near_ground_disc_in_field", v[i++], p.NearGroundElevationDeg(), "deg"});
  return out;
}

template <class T>
T ObjectiveOf(const Geometry<T>& g, Objective o) {
  switch (o) {
    case Objective::kSmallestSystem: return T(2) * g.c;
    case Objective::kWidestField: return -(g.upper - g.lower) / T(kDeg);
    case Objective::kLargestRim: return -g.rim_px;
    case Objective::kLongRange: return -g.long_range_res;
    case Objective::kNearGround: return -g.near_ground_mpx;
  }
  return T(0);
}

// Scale of each constraint for the solvers (so that a unit of each is comparable).
std::vector<double> ConstraintScales(const DesignProblem& p) {
  std::vector<double> s = {1.0, 10.0, 10.0};
  if (p.constraints.min_vertical_field_deg) s.push_back(1.0);
  if (p.constraints.min_rim_radius_px) s.push_back(10.0);
  if (p.constraints.max_system_length) s.push_back(0.001);
  if (p.constraints.rod_travel) s.insert(s.end(), {0.001, 0.001});
  if (p.objective == Objective::kLongRange || p.objective == Objective::kNearGround) s.push_back(1.0);
  return s;
}

double ObjectiveScale(Objective o) {
  switch (o) {
    case Objective::kSmallestSystem: return 0.001;
    case Objective::kWidestField: return 1.0;
    case Objective::kLargestRim: return 10.0;
    case Objective::kLongRange: return 0.1;
    case Objective::kNearGround: return 0.01;
  }
  return 1.0;
}

void CheckFinitePositive(double v, const std::string& where, const std::string& what) {
  HOVS_REQUIRE(std::isfinite(v), where, what, " must be a finite number");
  HOVS_REQUIRE(v > 0, where, what, " must be positive (got ", v, ")");
}

}  // namespace

const char* ToString(Objective o) {
  switch (o) {
    case Objective::kSmallestSystem: return "smallest_system";
    case Objective::kWidestField: return "widest_field";
    case Objective::kLargestRim: return "largest_rim";
    case Objective::kLongRange: return "long_range_resolution";
    case Objective::kNearGround: return "near_ground_coverage";
  }
  return "?";
}

std::optional<Objective> ObjectiveFromString(const std::string& s) {
  for (Objective o : {Objective::kSmallestSystem, Objective::kWidestField, Objective::kLargestRim,
                      Objective::kLongRange, Objective::kNearGround})
    if (s == ToString(o)) return o;
  return std::nullopt;
}

void CameraSpec::Check(const std::string& where) const {
  CheckFinitePositive(focal_length, where + ".focal_length", "focal length");
  CheckFinitePositive(pixel_pitch, where + ".pixel_pitch", "pixel pitch");
  CheckFinitePositive(lens_aperture, where + ".lens_aperture", "lens aperture");
  HOVS_REQUIRE(width > 0 && height > 0, where, "sensor size must be positive (got ", width, " x ", height, ")");
  Lens().Check(where + ".lens");
}

void BlurSpec::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(limit_px) && limit_px > 0, where + ".limit_px", "must be a positive blur in px (got ",
               limit_px, ")");
  HOVS_REQUIRE(std::isfinite(near) && near > 0 && !std::isnan(far) && far > near, where + ".scene_distance",
               "must be [near, far] with 0 < near < far (far may be infinity; got [", near, ", ", far, "])");
  if (max_rms_px)
    HOVS_REQUIRE(std::isfinite(*max_rms_px) && *max_rms_px > 0, where + ".max_blur_px",
                 "must be a positive blur in px (got ", *max_rms_px, ")");
}

double DesignProblem::NearGroundElevationDeg() const { return -std::atan2(mounting_height, near_ground_radius) / kDeg; }

double DesignProblem::RimLimitPx() const {
  return 0.5 * std::min(camera.width, camera.height) - constraints.rim_margin_px;
}

void DesignProblem::Check(const std::string& where) const {
  camera.Check(where + ".camera");
  blur.Check(where + ".blur");
  CheckFinitePositive(mounting_height, where + ".mounting_height", "mounting height");
  const auto check_range = [&](const Range& r, const std::string& name) {
    CheckFinitePositive(r.min, where + ".search." + name, name + " minimum");
    CheckFinitePositive(r.max, where + ".search." + name, name + " maximum");
    HOVS_REQUIRE(r.min <= r.max, where + ".search." + name, "minimum ", r.min, " exceeds maximum ", r.max);
  };
  check_range(a, "a");
  check_range(b, "b");
  check_range(d, "d");
  const Constraints& k = constraints;
  HOVS_REQUIRE(std::isfinite(k.max_upper_elevation_deg) && std::abs(k.max_upper_elevation_deg) < 90,
               where + ".constraints.max_upper_elevation_deg", "must be a finite angle in (-90, 90) degrees");
  HOVS_REQUIRE(std::isfinite(k.rim_margin_px) && k.rim_margin_px >= 0 && RimLimitPx() > 0,
               where + ".constraints.rim_margin_px", "must be >= 0 and leave a positive rim radius");
  if (k.min_vertical_field_deg)
    HOVS_REQUIRE(std::isfinite(*k.min_vertical_field_deg) && *k.min_vertical_field_deg > 0,
                 where + ".constraints.min_vertical_field_deg", "must be a positive angle");
  if (k.min_rim_radius_px)
    HOVS_REQUIRE(std::isfinite(*k.min_rim_radius_px) && *k.min_rim_radius_px > 0,
                 where + ".constraints.min_rim_radius_px", "must be positive");
  if (k.max_system_length)
    CheckFinitePositive(*k.max_system_length, where + ".constraints.max_system_length", "maximum system length");
  if (k.rod_travel) {
    CheckFinitePositive(k.rod_travel->min, where + ".constraints.rod_travel", "rod travel minimum");
    CheckFinitePositive(k.rod_travel->max, where + ".constraints.rod_travel", "rod travel maximum");
    HOVS_REQUIRE(k.rod_travel->min < k.rod_travel->max, where + ".constraints.rod_travel", "minimum ",
                 k.rod_travel->min, " must be below maximum ", k.rod_travel->max);
  }
  HOVS_REQUIRE(std::isfinite(long_range_elevation_deg) && std::abs(long_range_elevation_deg) < 90,
               where + ".long_range_elevation_deg", "must be a finite angle in (-90, 90) degrees");
  CheckFinitePositive(near_ground_radius, where + ".near_ground_radius", "near-ground radius");
}

void SweepSpec::Check(const std::string& where) const {
  HOVS_REQUIRE(na >= 2 && nb >= 2 && nd >= 1, where, "grid needs at least 2 x 2 points (got ", na, " x ", nb, ")");
  HOVS_REQUIRE(static_cast<double>(na) * nb * nd <= 5e7, where, "grid of ", na, " x ", nb, " x ", nd,
               " points is too large (at most 5e7)");
}

CatadioptricCamera<double> RigOf(const DesignPoint& p, const CameraSpec& camera) {
  return CatadioptricCamera<double>::Aligned(HyperboloidMirror<double>{p.a, p.b, p.d}, camera.Pinhole(),
                                             0.5 * camera.lens_aperture);
}

Metrics Evaluate(const DesignPoint& p, const DesignProblem& problem) {
  const Geometry<double> g = ComputeGeometry(p.a, p.b, p.d, problem);
  Metrics m;
  m.p = p;
  m.c = g.c;
  m.system_length = 2 * g.c;
  m.rim_z = g.rim_z;
  m.vertex_z = p.a - g.c;
  m.sag = m.rim_z - m.vertex_z;
  m.upper_deg = g.upper / kDeg;
  m.lower_deg = g.lower / kDeg;
  m.field_deg = m.upper_deg - m.lower_deg;
  m.rim_radius_px = g.rim_px;
  m.reflection_radius_px = g.reflection_px;
  m.ground_radius_inner = problem.mounting_height / std::tan(-g.lower);
  m.ground_radius_outer =
      g.upper < 0 ? problem.mounting_height / std::tan(-g.upper) : std::numeric_limits<double>::infinity();
  m.plate_height = g.rim_z + 2 * g.c;
  m.upper_px_per_deg = g.upper_res;
  m.long_range_px_per_deg = ScalarPart(g.upper) / kDeg >= problem.long_range_elevation_deg ? g.long_range_res : 0.0;
  m.near_ground_mpx = g.near_ground_mpx;
  return m;
}

std::vector<ConstraintValue> EvaluateConstraints(const Metrics& m, const DesignProblem& problem) {
  const Geometry<double> g = ComputeGeometry(m.p.a, m.p.b, m.p.d, problem);
  return DescribeConstraints(ConstraintVector(g, problem), problem);
}

double MaxViolation(const std::vector<ConstraintValue>& g) {
  double v = 0;
  for (const auto& c : g) v = std::max(v, c.value);
  return v;
}

double ObjectiveValue(const Metrics& m, Objective o) {
  switch (o) {
    case Objective::kSmallestSystem: return m.system_length;
    case Objective::kWidestField: return -m.field_deg;
    case Objective::kLargestRim: return -m.rim_radius_px;
    case Objective::kLongRange: return -m.long_range_px_per_deg;
    case Objective::kNearGround: return -m.near_ground_mpx;
  }
  return 0;
}

std::vector<ResolutionSample> RadialResolution(const DesignPoint& p, const CameraSpec& camera, int n) {
  HOVS_REQUIRE(n >= 2, "radial resolution", "needs at least 2 samples");
  using J = ceres::Jet<double, 1>;
  const CatadioptricCamera<J> rig = RigOf(p, camera).Cast<J>();
  const Geometry<double> g = ComputeGeometry(p.a, p.b, p.d, camera);
  std::vector<ResolutionSample> out;
  const double lo = g.lower + 1e-6, hi = g.upper - 1e-6;
  for (int i = 0; i < n; ++i) {
    const double e = lo + (hi - lo) * i / (n - 1);
    const J ej(e, 0);
    const Vec3<J> X(cos(ej), J(0), sin(ej));
    Vec2<J> uv;
    if (rig.ImgFromMirrorSvp(X, &uv) != ProjectionStatus::kOk) continue;
    const J rho = uv(0) - J(rig.camera.cx.a);
    out.push_back({e / kDeg, rho.a, std::abs(rho.v(0)) * kDeg});
  }
  return out;
}

std::optional<size_t> SweepResult::BestFeasible() const {
  std::optional<size_t> best;
  for (size_t i = 0; i < objective.size(); ++i)
    if (violated[i] == 0 && (!best || objective[i] < objective[*best])) best = i;
  return best;
}

SweepResult Sweep(const DesignProblem& problem, const SweepSpec& spec) {
  return SweepRows(problem, spec, 0, static_cast<size_t>(spec.nb) * spec.nd);
}

SweepResult SweepRows(const DesignProblem& problem, const SweepSpec& spec, size_t row_first, size_t row_end) {
  problem.Check("design");
  spec.Check("design.search.grid");
  SweepResult r;
  r.spec = spec;
  r.a = problem.a, r.b = problem.b, r.d = problem.d;
  if (spec.nd == 1) r.d.max = r.d.min;
  for (const auto& c : DescribeConstraints(std::vector<double>(ConstraintScales(problem).size(), 0.0), problem))
    r.constraint_names.push_back(c.name);
  const size_t n = static_cast<size_t>(spec.na) * spec.nb * spec.nd;
  for (auto* v : {&r.upper_deg, &r.lower_deg, &r.field_deg, &r.rim_px, &r.system_length, &r.objective}) v->resize(n);
  r.violated.resize(n);
  HOVS_REQUIRE(row_first <= row_end && row_end <= static_cast<size_t>(spec.nb) * spec.nd, "design sweep", "rows ",
               row_first, "..", row_end, " outside the grid's ", spec.nb * spec.nd);
  tbb::parallel_for(tbb::blocked_range<size_t>(row_first, row_end), [&](const tbb::blocked_range<size_t>& rows) {
    for (size_t row = rows.begin(); row != rows.end(); ++row) {
      const int ib = static_cast<int>(row % spec.nb), id = static_cast<int>(row / spec.nb);
      for (int ia = 0; ia < spec.na; ++ia) {
        const size_t k = r.Index(ia, ib, id);
        const Geometry<double> g = ComputeGeometry(r.A(ia), r.B(ib), r.D(id), problem);
        r.upper_deg[k] = g.upper / kDeg;
        r.lower_deg[k] = g.lower / kDeg;
        r.field_deg[k] = (g.upper - g.lower) / kDeg;
        r.rim_px[k] = g.rim_px;
        r.system_length[k] = 2 * g.c;
        r.objective[k] = ObjectiveOf(g, problem.objective);
        const std::vector<double> cv = ConstraintVector(g, problem);
        uint32_t bits = 0;
        for (size_t j = 0; j < cv.size(); ++j)
          if (!(cv[j] <= 0)) bits |= 1u << j;
        r.violated[k] = bits;
      }
    }
  });
  return r;
}

// ---- Continuous optimum ------------------------------------------------------------------------------
namespace {

struct SolverContext {
  const DesignProblem* problem;
  std::vector<int> free;  // indices into (a, b, d) that the solver moves
  DesignPoint fixed;
  size_t k = 0;  // constraint index for the constraint callbacks
  int evaluations = 0;
};

template <class T>
void Unpack(const SolverContext& ctx, const T* x, T* abd) {
  abd[0] = T(ctx.fixed.a), abd[1] = T(ctx.fixed.b), abd[2] = T(ctx.fixed.d);
  for (size_t i = 0; i < ctx.free.size(); ++i) abd[ctx.free[i]] = x[i];
}

// Evaluates objective (k < 0) or constraint k (scaled), with gradient through Jets when asked.
double Scaled(const std::vector<double>& x, std::vector<double>& grad, SolverContext* ctx, int k) {
  using J = ceres::Jet<double, 3>;
  ++ctx->evaluations;
  const DesignProblem& p = *ctx->problem;
  const double scale = k < 0 ? ObjectiveScale(p.objective) : ConstraintScales(p)[k];
  if (!grad.empty()) {
    J xj[3], abd[3];
    for (size_t i = 0; i < x.size(); ++i) xj[i] = J(x[i], static_cast<int>(i));
    Unpack(*ctx, xj, abd);
    const Geometry<J> g = ComputeGeometry(abd[0], abd[1], abd[2], p);
    const J v = k < 0 ? ObjectiveOf(g, p.objective) : ConstraintVector(g, p)[k];
    for (size_t i = 0; i < x.size(); ++i) grad[i] = v.v(static_cast<int>(i)) / scale;
    return v.a / scale;
  }
  double abd[3];
  Unpack(*ctx, x.data(), abd);
  const Geometry<double> g = ComputeGeometry(abd[0], abd[1], abd[2], p);
  const double v = k < 0 ? ObjectiveOf(g, p.objective) : ConstraintVector(g, p)[k];
  return v / scale;
}

struct ConstraintData {
  SolverContext* ctx;
  int k;
};

double ObjectiveCallback(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  return Scaled(x, grad, static_cast<SolverContext*>(data), -1);
}
double ConstraintCallback(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  auto* cd = static_cast<ConstraintData*>(data);
  return Scaled(x, grad, cd->ctx, cd->k);
}

DesignPoint Pack(const SolverContext& ctx, const std::vector<double>& x) {
  double abd[3];
  Unpack(ctx, x.data(), abd);
  return {abd[0], abd[1], abd[2]};
}

Optimum MakeOptimum(const DesignPoint& p, const DesignProblem& problem) {
  Optimum o;
  o.metrics = Evaluate(p, problem);
  o.constraints = EvaluateConstraints(o.metrics, problem);
  o.objective = ObjectiveValue(o.metrics, problem.objective);
  o.max_violation = MaxViolation(o.constraints);
  return o;
}

// Moves an infeasible point towards a feasible anchor by bisection until it is feasible (g <= 0 exactly).
DesignPoint Repair(const DesignPoint& bad, const DesignPoint& anchor, const DesignProblem& problem) {
  double lo = 0, hi = 1;  // fraction of the way from bad to anchor; hi is feasible
  const auto at = [&](double t) {
    return DesignPoint{bad.a + t * (anchor.a - bad.a), bad.b + t * (anchor.b - bad.b), bad.d + t * (anchor.d - bad.d)};
  };
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (MaxViolation(EvaluateConstraints(Evaluate(at(mid), problem), problem)) <= 0)
      hi = mid;
    else
      lo = mid;
  }
  return at(hi);
}

std::string ShortNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::string NloptResultName(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS: return "success";
    case nlopt::STOPVAL_REACHED: return "stopval reached";
    case nlopt::FTOL_REACHED: return "ftol reached";
    case nlopt::XTOL_REACHED: return "xtol reached";
    case nlopt::MAXEVAL_REACHED: return "maxeval reached";
    case nlopt::MAXTIME_REACHED: return "maxtime reached";
    default: return "code " + std::to_string(static_cast<int>(r));
  }
}

}  // namespace

Optimum OptimizeContinuous(const DesignProblem& problem, const SweepResult& sweep) {
  problem.Check("design");
  SolverContext ctx;
  ctx.problem = &problem;
  const Range* ranges[3] = {&problem.a, &problem.b, &problem.d};
  DesignPoint start{0.5 * (problem.a.min + problem.a.max), 0.5 * (problem.b.min + problem.b.max),
                    0.5 * (problem.d.min + problem.d.max)};
  const std::optional<size_t> best = sweep.BestFeasible();
  bool start_feasible = false;
  if (best) {
    const size_t k = *best;
    const int ia = static_cast<int>(k % sweep.spec.na), ib = static_cast<int>((k / sweep.spec.na) % sweep.spec.nb),
              id = static_cast<int>(k / (static_cast<size_t>(sweep.spec.na) * sweep.spec.nb));
    start = {sweep.A(ia), sweep.B(ib), sweep.D(id)};
    start_feasible = true;
  }
  ctx.fixed = start;
  for (int i = 0; i < 3; ++i)
    if (!ranges[i]->Fixed()) ctx.free.push_back(i);
  HOVS_REQUIRE(!ctx.free.empty(), "design.search", "every parameter is fixed: nothing to optimise");

  const size_t nc = ConstraintScales(problem).size();
  std::vector<ConstraintData> cdata(nc);
  for (size_t k = 0; k < nc; ++k) cdata[k] = {&ctx, static_cast<int>(k)};

  std::vector<Optimum> candidates;
  std::vector<std::string> log;
  if (start_feasible) {
    Optimum s = MakeOptimum(start, problem);
    s.method = "best feasible sweep point";
    candidates.push_back(s);
  }
  const auto run = [&](nlopt::algorithm algo, const DesignPoint& from, const std::string& label) {
    const unsigned dim = static_cast<unsigned>(ctx.free.size());
    nlopt::opt opt(algo, dim);
    std::vector<double> lb, ub, x, step;
    for (int i : ctx.free) {
      lb.push_back(ranges[i]->min);
      ub.push_back(ranges[i]->max);
      x.push_back(i == 0 ? from.a : i == 1 ? from.b : from.d);
      step.push_back(0.02 * (ranges[i]->max - ranges[i]->min) + 1e-6);
    }
    opt.set_lower_bounds(lb);
    opt.set_upper_bounds(ub);
    opt.set_min_objective(ObjectiveCallback, &ctx);
    for (size_t k = 0; k < nc; ++k) opt.add_inequality_constraint(ConstraintCallback, &cdata[k], 0.0);
    opt.set_xtol_abs(1e-13);
    opt.set_ftol_abs(1e-14);
    opt.set_maxeval(20000);
    if (algo == nlopt::LN_COBYLA) opt.set_initial_step(step);
    double f = 0;
    const int before = ctx.evaluations;
    std::string status;
    try {
      status = NloptResultName(opt.optimize(x, f));
    } catch (const nlopt::roundoff_limited&) {
      status = "roundoff limited";  // x holds the last point; it is verified below like any other
    } catch (const std::exception& e) {
      log.push_back(label + ": failed (" + std::string(e.what()) + ")");
      return;
    }
    Optimum o = MakeOptimum(Pack(ctx, x), problem);
    o.evaluations = ctx.evaluations - before;
    o.method = label;
    std::string line = label + ": " + status + ", " + std::to_string(o.evaluations) + " evaluations, max violation " +
                       ShortNumber(o.max_violation);
    if (o.max_violation > 0 && start_feasible) {
      // COBYLA and SLSQP may stop slightly outside the feasible set: pull back towards the feasible start.
      Optimum repaired = MakeOptimum(Repair(o.metrics.p, start, problem), problem);
      repaired.evaluations = o.evaluations;
      repaired.method = label + " + feasibility repair";
      line += "; repaired to max violation " + ShortNumber(repaired.max_violation);
      o = repaired;
    }
    log.push_back(line);
    if (o.max_violation <= 0) candidates.push_back(o);
  };
  run(nlopt::LN_COBYLA, start, "COBYLA");
  if (!candidates.empty()) run(nlopt::LD_SLSQP, candidates.back().metrics.p, "SLSQP (from best so far)");
  run(nlopt::LD_SLSQP, start, "SLSQP");

  if (candidates.empty()) {
    std::string why = "no design in the search box satisfies the constraints";
    if (!start_feasible) why += " (no feasible point on the sweep grid either)";
    throw Error(
        "design optimisation", why + "; solver log: " + [&] {
          std::string s;
          for (const auto& l : log) s += "[" + l + "] ";
          return s;
        }());
  }
  Optimum best_o = *std::min_element(candidates.begin(), candidates.end(),
                                     [](const Optimum& x, const Optimum& y) { return x.objective < y.objective; });
  best_o.solver_log = log;
  return best_o;
}

std::optional<Optimum> OptimizeIntegerMillimetre(const DesignProblem& problem) {
  problem.Check("design");
  const auto mm_range = [](const Range& r) {
    return std::pair<int, int>(static_cast<int>(std::ceil(r.min * 1000 - 1e-9)),
                               static_cast<int>(std::floor(r.max * 1000 + 1e-9)));
  };
  const auto [a0, a1] = mm_range(problem.a);
  const auto [b0, b1] = mm_range(problem.b);
  std::pair<int, int> dr = mm_range(problem.d);
  std::vector<double> ds;
  if (problem.d.Fixed())
    ds.push_back(problem.d.min);
  else
    for (int d = dr.first; d <= dr.second; ++d) ds.push_back(d * 1e-3);
  std::optional<Optimum> best;
  for (double d : ds)
    for (int a = a0; a <= a1; ++a)
      for (int b = b0; b <= b1; ++b) {
        const DesignPoint p{a * 1e-3, b * 1e-3, d};
        const Metrics m = Evaluate(p, problem);
        const auto g = EvaluateConstraints(m, problem);
        if (MaxViolation(g) > 0) continue;
        const double obj = ObjectiveValue(m, problem.objective);
        if (!best || obj < best->objective - 1e-15) {
          best = MakeOptimum(p, problem);
          best->method = "integer-millimetre enumeration";
        }
      }
  return best;
}

}  // namespace hovs::design
