#include "study/tolerance.h"

#include <tbb/parallel_for.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/any_model.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "core/progress.h"
#include "core/statistics.h"
#include "core/yaml_reader.h"
#include "depth/stereo.h"
#include "unwrap/layout.h"

namespace hovs::study {
namespace fs = std::filesystem;

const std::vector<Parameter>& Parameters() {
  static const std::vector<Parameter> p = {
      {"mirror_a", "mm", "the hyperboloid's a", 1},
      {"mirror_b", "mm", "the hyperboloid's b", 1},
      {"rim_diameter", "mm", "the mirror's rim diameter", 1},
      {"mirror_tilt", "deg", "the mirror's axis against the optical axis, about x and y", 2},
      {"lateral_offset", "mm", "the pinhole off the mirror's second focus across the axis, x and y", 2},
      {"height", "mm", "the pinhole off the second focus along the axis", 1},
      {"focal_length", "%", "the lens' focal length against its nominal value", 1},
      {"principal_point", "px", "the principal point off the image centre, u and v", 2}};
  return p;
}

const std::vector<Metric>& Metrics() {
  static const std::vector<Metric> m = {
      {"ray_error_deg", "deg", "worst angle between a pixel's nominal bearing and its true ray"},
      {"svp_deviation_mm", "mm", "worst distance of the true rays from their common nearest point"},
      {"view_error_px", "px", "worst displacement in the article's six views (points at view_range)"},
      {"depth_error_percent", "%", "worst relative range error of the two-unit rig"}};
  return m;
}

namespace {

constexpr double kDeg = M_PI / 180;
constexpr double kFailed = std::numeric_limits<double>::quiet_NaN();
// The share of a figure's grid an erroneous unit must evaluate for the figure to count (SampleFigures).
constexpr double kMinCoverage = 0.9;

int ParameterIndex(const std::string& name) {
  for (size_t i = 0; i < Parameters().size(); ++i)
    if (Parameters()[i].name == name) return static_cast<int>(i);
  return -1;
}

std::string KnownNames(bool metrics) {
  std::string s;
  if (metrics)
    for (const auto& m : Metrics()) s += (s.empty() ? "" : ", ") + m.name;
  else
    for (const auto& p : Parameters()) s += (s.empty() ? "" : ", ") + p.name;
  return s;
}

// Component values (the parameter's unit) -> SI errors.
void SetComponent(UnitErrors* e, int parameter, int component, double v) {
  switch (parameter) {
    case 0: e->a = 1e-3 * v; break;
    case 1: e->b = 1e-3 * v; break;
    case 2: e->rim = 1e-3 * v; break;
    case 3: e->tilt[component] = v * kDeg; break;
    case 4: e->offset[component] = 1e-3 * v; break;
    case 5: e->offset.z() = 1e-3 * v; break;
    case 6: e->focal = 0.01 * v; break;
    case 7: e->principal_point[component] = v; break;
  }
}

// SplitMix64: a stream of 64-bit values from one state (Steele, Lea, Flood 2014).
struct SplitMix64 {
  uint64_t state;
  uint64_t Next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return (Next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

// The largest size a tolerance may have, in its parameter's unit, and why: beyond it a unit is not the nominal
// design with errors but another design (and most of its figures fail).
std::pair<double, std::string> LargestTolerance(const std::string& name, const design::DesignPoint& p,
                                                const design::CameraSpec& camera) {
  const double c = std::sqrt(p.a * p.a + p.b * p.b);
  if (name == "mirror_a") return {0.05e3 * p.a, "5 % of the nominal a"};
  if (name == "mirror_b") return {0.05e3 * p.b, "5 % of the nominal b"};
  if (name == "rim_diameter") return {0.05e3 * p.d, "5 % of the nominal rim diameter"};
  if (name == "mirror_tilt") return {5.0, "5 degrees"};
  if (name == "lateral_offset") return {0.05e3 * p.d, "5 % of the rim diameter"};
  if (name == "height") return {0.05e3 * 2 * c, "5 % of the distance 2c between the foci"};
  if (name == "focal_length") return {10.0, "10 % of the focal length"};
  return {0.05 * std::min(camera.width, camera.height), "5 % of the image's shorter side"};
}

}  // namespace

void ToleranceConfig::Check(const std::string& where) const {
  design.problem.Check(where + " (design)");
  HOVS_REQUIRE(nominal.a > 0 && nominal.b > 0 && nominal.d > 0, where, "the nominal design needs a, b, d > 0");
  for (const auto& [key, t] : tolerances) {
    HOVS_REQUIRE(ParameterIndex(key) >= 0, where + " (tolerances)", "unknown parameter '", key,
                 "' (known: ", KnownNames(false), ")");
    HOVS_REQUIRE(std::isfinite(t.size) && t.size >= 0, where + " (tolerances." + key + ")",
                 "must be a finite size >= 0");
    const auto [most, why] = LargestTolerance(key, nominal, design.problem.camera);
    HOVS_REQUIRE(t.size <= most, where + " (tolerances." + key + ")", FormatNumber("%g", t.size), " ",
                 Parameters()[ParameterIndex(key)].unit, " is not a manufacturing tolerance: at most ",
                 FormatNumber("%.4g", most), " (", why,
                 "); an error this large makes another design, which hovs design studies");
  }
  HOVS_REQUIRE(std::isfinite(view_range) && view_range > 0.2 && view_range <= 1e4, where + " (view_range)",
               "must be in (0.2, 10000] m");
  HOVS_REQUIRE(std::isfinite(baseline) && baseline > 0.01 && baseline <= 100, where + " (baseline)",
               "must be in (0.01, 100] m");
  HOVS_REQUIRE(!depth_ranges.empty() && depth_ranges.size() <= 16, where + " (depth_ranges)", "needs 1 to 16 ranges");
  for (double r : depth_ranges)
    HOVS_REQUIRE(std::isfinite(r) && r > 2 * baseline && r <= 1e4, where + " (depth_ranges)",
                 "each range must exceed twice the baseline and stay within 10 km (got ", r, ")");
  for (const auto& [key, v] : limits) {
    bool known = false;
    for (const auto& m : Metrics()) known |= m.name == key;
    HOVS_REQUIRE(known, where + " (limits)", "unknown figure '", key, "' (known: ", KnownNames(true), ")");
    HOVS_REQUIRE(std::isfinite(v) && v > 0, where + " (limits." + key + ")", "must be positive");
  }
}

ToleranceConfig ParseToleranceConfig(const std::string& text, const std::string& source, const fs::path& base_dir,
                                     const design::DesignConfig* design_override) {
  return WithYamlErrors(source, [&] {
    const YamlReader r(source);
    const YAML::Node root = r.Load(text);
    HOVS_REQUIRE(root.IsMap(), source, "expected a YAML mapping at the top level");
    r.OnlyKeys(root, "", {"name", "design", "seed", "tolerances", "evaluation", "limits"});
    ToleranceConfig c;
    c.source = source, c.text = text;
    if (root["name"]) c.name = r.Name(root["name"], "name");
    HOVS_REQUIRE(root["design"] || design_override, source,
                 "needs 'design': the design config whose marked design is the nominal");
    c.design =
        design_override ? *design_override : design::LoadDesignConfig(base_dir / r.String(root["design"], "design"));
    HOVS_REQUIRE(c.design.marked.has_value(), c.design.source,
                 "the design config has no marked_design: the "
                 "tolerance study needs one nominal design");
    c.nominal = *c.design.marked;
    if (root["seed"]) c.seed = r.Seed(root["seed"], "seed");
    if (const YAML::Node t = root["tolerances"]) {
      HOVS_REQUIRE(t.IsMap(), r.Where(t, "tolerances"), "expected a mapping of parameter: {normal|uniform: size}");
      for (const auto& kv : t) {
        const std::string name = kv.first.as<std::string>(), key = "tolerances." + name;
        HOVS_REQUIRE(ParameterIndex(name) >= 0, r.Where(kv.second, key), "unknown parameter '", name,
                     "' (known: ", KnownNames(false), ")");
        r.OnlyKeys(kv.second, key, {"normal", "uniform"});
        HOVS_REQUIRE(kv.second.size() == 1, r.Where(kv.second, key),
                     "give exactly one of normal (standard "
                     "deviation) or uniform (half-width)");
        Tolerance tol;
        tol.distribution = kv.second["normal"] ? Distribution::kNormal : Distribution::kUniform;
        const char* dist = tol.distribution == Distribution::kNormal ? "normal" : "uniform";
        tol.size = r.Number(kv.second[dist], key + "." + dist);
        HOVS_REQUIRE(tol.size >= 0, r.Where(kv.second, key), "the size must be >= 0");
        c.tolerances[name] = tol;
      }
    }
    if (const YAML::Node e = root["evaluation"]) {
      r.OnlyKeys(e, "evaluation", {"view_range", "depth_ranges", "baseline"});
      if (e["view_range"]) c.view_range = r.Positive(e["view_range"], "evaluation.view_range");
      if (e["baseline"]) c.baseline = r.Positive(e["baseline"], "evaluation.baseline");
      if (const YAML::Node d = e["depth_ranges"]) {
        HOVS_REQUIRE(d.IsSequence(), r.Where(d, "evaluation.depth_ranges"), "expected a list of ranges (m)");
        c.depth_ranges.clear();
        for (size_t i = 0; i < d.size(); ++i)
          c.depth_ranges.push_back(r.Positive(d[i], "evaluation.depth_ranges[" + std::to_string(i) + "]"));
      }
    }
    if (const YAML::Node l = root["limits"]) {
      HOVS_REQUIRE(l.IsMap(), r.Where(l, "limits"), "expected a mapping of figure: limit");
      for (const auto& kv : l) c.limits[kv.first.as<std::string>()] = r.Positive(kv.second, "limits");
    }
    c.Check(source);
    return c;
  });
}

ToleranceConfig LoadToleranceConfig(const fs::path& path, const design::DesignConfig* design_override) {
  RequireFile(path, "tolerance config");
  return ParseToleranceConfig(ReadFile(path, size_t(1) << 20), path.string(), path.parent_path(), design_override);
}

UnitErrors UnitErrors::Scaled(double k) const {
  UnitErrors e = *this;
  e.a *= k, e.b *= k, e.rim *= k, e.tilt *= k, e.offset *= k, e.focal *= k, e.principal_point *= k;
  return e;
}

UnitErrors SingleError(const std::string& parameter, double size) {
  const int p = ParameterIndex(parameter);
  HOVS_REQUIRE(p >= 0, "tolerance", "unknown parameter '", parameter, "'");
  UnitErrors e;
  SetComponent(&e, p, 0, size);
  return e;
}

CatadioptricCamera<double> ErroneousRig(const design::DesignPoint& p, const design::CameraSpec& camera,
                                        const UnitErrors& e) {
  const HyperboloidMirror<double> mirror{p.a + e.a, p.b + e.b, p.d + e.rim};
  PinholeCamera<double> cam = camera.Pinhole();
  cam.fx *= 1 + e.focal, cam.fy *= 1 + e.focal;
  cam.cx += e.principal_point.x(), cam.cy += e.principal_point.y();
  CatadioptricCamera<double> rig = CatadioptricCamera<double>::Aligned(mirror, cam, 0.5 * camera.lens_aperture);
  // The mirror sits by its rim on the plate, which stands at the nominal height above the pinhole: a mirror of
  // other a, b or rim puts its second focus off the pinhole by the change of its plate height (z_rim + 2c).
  const HyperboloidMirror<double> nominal{p.a, p.b, p.d};
  const double plate_shift = (mirror.RimZ() + 2 * mirror.c()) - (nominal.RimZ() + 2 * nominal.c());
  rig.cam_from_mirror =
      CamFromMirrorMisaligned<double>(mirror, Vec3d(e.tilt.x(), e.tilt.y(), 0), e.offset + Vec3d(0, 0, plate_shift));
  return rig;
}

UnitErrors DrawErrors(const ToleranceConfig& config, int64_t index, int unit) {
  SplitMix64 rng{config.seed ^ (static_cast<uint64_t>(index) * 0xD1B54A32D192ED03ull) ^
                 (static_cast<uint64_t>(unit + 1) * 0x8CB92BA72F3D8DD7ull)};
  UnitErrors e;
  // Every component draws two uniforms whether or not it has a tolerance, so a parameter's draws do not depend on
  // which others the config lists.
  for (size_t p = 0; p < Parameters().size(); ++p)
    for (int k = 0; k < Parameters()[p].components; ++k) {
      const double u1 = rng.Uniform(), u2 = rng.Uniform();
      const auto it = config.tolerances.find(Parameters()[p].name);
      if (it == config.tolerances.end() || it->second.size == 0) continue;
      const double z = it->second.distribution == Distribution::kNormal
                           ? std::sqrt(-2 * std::log1p(-u1)) * std::cos(2 * M_PI * u2)  // Box-Muller
                           : 2 * u1 - 1;
      SetComponent(&e, static_cast<int>(p), k, it->second.size * z);
    }
  return e;
}

struct ToleranceEvaluator::Impl {
  const ToleranceConfig config;
  CatadioptricCamera<double> nominal;
  std::vector<Vec2d> field_pixels;              // the annulus grid
  std::vector<Vec3d> field_bearings;            // their nominal bearings, camera frame
  std::vector<VirtualView<double>> views;       // the article's six
  std::vector<std::vector<Vec2d>> view_pixels;  // 9 x 5 per view, where the nominal model sees
  std::vector<Vec3d> depth_points;              // left mirror frame
  depth::StereoRig stereo;

  explicit Impl(const ToleranceConfig& c) : config(c) {
    nominal = design::RigOf(c.nominal, c.design.problem.camera);
    const design::Metrics m = design::Evaluate(c.nominal, c.design.problem);
    const double r0 = m.reflection_radius_px + 0.05 * (m.rim_radius_px - m.reflection_radius_px);
    const double r1 = m.rim_radius_px - 0.03 * (m.rim_radius_px - m.reflection_radius_px);
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 36; ++j) {
        const double r = r0 + (r1 - r0) * i / 11.0, phi = 2 * M_PI * j / 36.0;
        const Vec2d uv(nominal.camera.cx + r * std::cos(phi), nominal.camera.cy + r * std::sin(phi));
        Vec3d b;
        if (!nominal.CamFromImg(uv, &b)) continue;
        field_pixels.push_back(uv);
        field_bearings.push_back(nominal.cam_from_mirror.rotation * b);
      }
    HOVS_REQUIRE(field_pixels.size() > 100, c.source, "the nominal design images too little of its mirror");
    const AnyModel model = AnyModel::Exact(nominal);
    for (const auto& spec : unwrap::PresetLayout("article", model).views) {
      views.push_back(spec.View());
      std::vector<Vec2d> px;
      for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 5; ++j) {
          const Vec2d q((0.05 + 0.9 * i / 8.0) * (spec.width - 1), (0.05 + 0.9 * j / 4.0) * (spec.height - 1));
          Vec3d b;
          Vec2d uv;
          // Only view pixels the nominal unit sees.
          if (views.back().MirrorFromImg(q, &b) &&
              nominal.ImgFromMirror(c.view_range * b, &uv) == ProjectionStatus::kOk)
            px.push_back(q);
        }
      view_pixels.push_back(px);
    }
    for (double range : c.depth_ranges)
      for (double az : {45.0, 90.0, 135.0, 225.0, 270.0, 315.0})
        for (double el : {-10.0, -25.0})
          depth_points.push_back(range * Vec3d(std::cos(el * kDeg) * std::cos(az * kDeg),
                                               std::cos(el * kDeg) * std::sin(az * kDeg), std::sin(el * kDeg)));
    stereo.left = stereo.right = model;
    stereo.right_from_left = Rigid3d::Translation(Vec3d(-c.baseline, 0, 0));
  }

  // Where the erroneous unit images X (nominal mirror frame), and the nominal bearing of that pixel.
  bool SeenBearing(const CatadioptricCamera<double>& rig, const Vec3d& X, Vec3d* bearing) const {
    const Vec3d Xt = rig.cam_from_mirror.Inverse() * (nominal.cam_from_mirror * X);
    Vec2d uv;
    if (rig.ImgFromMirror(Xt, &uv) != ProjectionStatus::kOk) return false;
    return nominal.CamFromImg(uv, bearing);
  }

  SampleFigures Evaluate(const UnitErrors& left, const UnitErrors& right) const {
    SampleFigures f;
    // A figure is the worst over its grid; where the erroneous unit cannot evaluate most of the grid (its mirror
    // no longer covers the pixels, the points leave the image), the figure failed: NaN, never a small worst.
    const auto covered = [](size_t evaluated, size_t total) {
      return total > 0 && static_cast<double>(evaluated) >= kMinCoverage * static_cast<double>(total);
    };
    const auto rig = ErroneousRig(config.nominal, config.design.problem.camera, left);
    // Ray error and the caustic's extent.
    std::vector<Vec3d> origins, dirs;
    Mat3<double> A = Mat3<double>::Zero();
    Vec3d rhs = Vec3d::Zero();
    for (size_t i = 0; i < field_pixels.size(); ++i) {
      Vec3d M, d;
      if (!rig.RayFromImg(field_pixels[i], &M, &d)) continue;
      f.values[0] = std::max(f.values[0], AngleBetweenDeg(field_bearings[i], rig.cam_from_mirror.rotation * d));
      const Mat3<double> P = Mat3<double>::Identity() - d * d.transpose();
      A += P, rhs += P * M;
      origins.push_back(M), dirs.push_back(d);
    }
    if (origins.size() >= 3) {
      const Vec3d p = A.ldlt().solve(rhs);
      for (size_t i = 0; i < origins.size(); ++i) {
        const Vec3d v = p - origins[i];
        f.values[1] = std::max(f.values[1], 1e3 * (v - v.dot(dirs[i]) * dirs[i]).norm());
      }
    }
    if (!covered(origins.size(), field_pixels.size()) || !std::isfinite(f.values[0]) || !std::isfinite(f.values[1]))
      f.values[0] = f.values[1] = kFailed;
    // The six views.
    size_t view_total = 0, view_done = 0;
    for (size_t k = 0; k < views.size(); ++k)
      for (const Vec2d& q : view_pixels[k]) {
        ++view_total;
        Vec3d b, seen;
        Vec2d q2;
        if (!views[k].MirrorFromImg(q, &b) || !SeenBearing(rig, config.view_range * b, &seen) ||
            !views[k].ImgFromMirror(seen, &q2))
          continue;
        ++view_done;
        f.values[2] = std::max(f.values[2], (q2 - q).norm());
      }
    if (!covered(view_done, view_total) || !std::isfinite(f.values[2])) f.values[2] = kFailed;
    // The two-unit rig.
    const auto rig_right = ErroneousRig(config.nominal, config.design.problem.camera, right);
    const Vec3d right_centre(config.baseline, 0, 0);
    size_t depth_done = 0;
    for (const Vec3d& X : depth_points) {
      Vec3d bl, br;
      if (!SeenBearing(rig, X, &bl) || !SeenBearing(rig_right, X - right_centre, &br)) continue;
      const depth::Triangulation t = depth::Triangulate(stereo, bl, br, 0.0);
      if (!t.ok) continue;
      ++depth_done;
      f.values[3] = std::max(f.values[3], 100 * std::abs(t.range_left - X.norm()) / X.norm());
    }
    if (!covered(depth_done, depth_points.size()) || !std::isfinite(f.values[3])) f.values[3] = kFailed;
    return f;
  }
};

ToleranceEvaluator::ToleranceEvaluator(const ToleranceConfig& config) : impl_(new Impl(config)) {}
ToleranceEvaluator::~ToleranceEvaluator() = default;
SampleFigures ToleranceEvaluator::Evaluate(const UnitErrors& left, const UnitErrors& right) const {
  return impl_->Evaluate(left, right);
}

std::vector<Sample> RunSamples(const ToleranceConfig& config, int64_t count, int shard_index, int shard_count,
                               bool progress) {
  HOVS_REQUIRE(count >= 1 && count <= 10000000, "--samples", "must be in 1..10000000 (got ", count, ")");
  HOVS_REQUIRE(shard_count >= 1 && shard_count <= count && shard_index >= 0 && shard_index < shard_count, "--shard",
               "needs 0 <= index < shards <= samples");
  const int64_t first = count * shard_index / shard_count, end = count * (shard_index + 1) / shard_count;
  const ToleranceEvaluator evaluator(config);
  std::vector<Sample> samples(static_cast<size_t>(end - first));
  // In blocks of 4096 samples, each in parallel, with a progress line between blocks.
  const int64_t n = end - first, block = 4096;
  const ProgressLine line("sample", static_cast<size_t>(n), progress && n > block);
  for (int64_t b0 = 0; b0 < n; b0 += block) {
    line.Step(static_cast<size_t>(b0 + 1), static_cast<size_t>(b0), static_cast<size_t>(n - b0));
    tbb::parallel_for(b0, std::min(n, b0 + block), [&](int64_t k) {
      Sample& s = samples[static_cast<size_t>(k)];
      s.index = first + k;
      s.left = DrawErrors(config, s.index, 0);
      s.right = DrawErrors(config, s.index, 1);
      s.figures = evaluator.Evaluate(s.left, s.right);
    });
  }
  return samples;
}

}  // namespace hovs::study
