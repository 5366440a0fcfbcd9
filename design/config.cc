#include "design/config.h"

#include <yaml-cpp/yaml.h>

#include <cmath>

#include "core/error.h"
#include "core/io.h"
#include "core/yaml_reader.h"

namespace hovs::design {
namespace {
std::string KnownObjectives() {
  std::string s;
  for (Objective o : {Objective::kSmallestSystem, Objective::kWidestField, Objective::kLargestRim,
                      Objective::kLongRange, Objective::kNearGround})
    s += (s.empty() ? "" : ", ") + std::string(ToString(o));
  return s;
}

std::vector<FamilyMember> ParseFamily(const YamlReader& r, const YAML::Node& f) {
  std::vector<FamilyMember> out;
  HOVS_REQUIRE(f.IsSequence() && f.size() >= 1 && f.size() <= 16, r.Where(f, "family"),
               "expected a list of 1 to 16 mirrors, each {name, objective, purpose}");
  for (size_t i = 0; i < f.size(); ++i) {
    const std::string key = "family[" + std::to_string(i) + "]";
    r.OnlyKeys(f[i], key, {"name", "objective", "purpose"});
    HOVS_REQUIRE(f[i]["name"] && f[i]["objective"], r.Where(f[i], key), "needs a name and an objective");
    FamilyMember m;
    m.name = r.String(f[i]["name"], key + ".name");
    HOVS_REQUIRE(!m.name.empty() && m.name.find_first_of("/\\ ") == std::string::npos, r.Where(f[i], key),
                 "name must be non-empty without spaces or slashes");
    for (const auto& other : out)
      HOVS_REQUIRE(other.name != m.name, r.Where(f[i], key), "mirror name '", m.name, "' is given twice");
    const std::string o = r.String(f[i]["objective"], key + ".objective");
    const auto obj = ObjectiveFromString(o);
    HOVS_REQUIRE(obj.has_value(), r.Where(f[i]["objective"], key + ".objective"), "unknown objective '", o,
                 "' (known: ", KnownObjectives(), ")");
    m.objective = *obj;
    if (f[i]["purpose"]) m.purpose = r.String(f[i]["purpose"], key + ".purpose");
    out.push_back(m);
  }
  return out;
}

Range RangeOf(const YamlReader& r, const YAML::Node& n, const std::string& key) {
  if (n.IsScalar()) {
    const double v = r.Number(n, key);
    return {v, v};
  }
  HOVS_REQUIRE(n.IsSequence() && n.size() == 2, r.Where(n, key), "expected [min, max] or a single value");
  return {r.Number(n[0], key + "[0]"), r.Number(n[1], key + "[1]")};
}
}  // namespace

namespace {
// lens: the thin lens (f_number: auto leaves the f-number to the design); blur: the blur figures' limit and
// scene distances.
void ParseLensAndBlur(const YamlReader& r, const YAML::Node& root, DesignProblem* problem) {
  DesignProblem& p = *problem;
  if (root["lens"]) {
    // f_number: auto leaves the f-number to the design (BlurSpec::auto_f_number); the rest is the lens.
    YAML::Node lens = root["lens"];
    if (lens.IsMap() && lens["f_number"] && lens["f_number"].IsScalar() && lens["f_number"].Scalar() == "auto") {
      lens = YAML::Clone(lens);
      lens.remove("f_number");
      p.blur.auto_f_number = true;
    }
    p.camera.lens = r.Lens(lens, "lens", p.camera.focal_length);
  }
  if (root["blur"]) {
    const YAML::Node b = root["blur"];
    r.OnlyKeys(b, "blur", {"limit_px", "scene_distance"});
    if (b["limit_px"]) p.blur.limit_px = r.Positive(b["limit_px"], "blur.limit_px");
    if (b["scene_distance"]) {
      const YAML::Node d = b["scene_distance"];
      HOVS_REQUIRE(d.IsSequence() && d.size() == 2, r.Where(d, "blur.scene_distance"),
                   "expected [near, far] in metres from F1 (far may be infinity)");
      p.blur.near = r.Positive(d[0], "blur.scene_distance[0]");
      p.blur.far = r.DistanceOrInfinity(d[1], "blur.scene_distance[1]");
      HOVS_REQUIRE(p.blur.far > p.blur.near, r.Where(d, "blur.scene_distance"), "far must exceed near");
    }
  }
}

DesignConfig ParseDesignConfigUnguarded(const std::string& text, const std::string& source) {
  const YamlReader r(source);
  const YAML::Node root = r.Load(text);
  HOVS_REQUIRE(root.IsMap(), source, "expected a YAML mapping at the top level");
  r.OnlyKeys(root, "",
             {"name", "camera", "mirror", "mounting_height", "constraints", "objective", "search", "marked_design",
              "resolution_samples", "long_range_elevation_deg", "near_ground_radius", "family", "lens", "blur"});
  DesignConfig cfg;
  cfg.source = source;
  cfg.text = text;
  DesignProblem& p = cfg.problem;
  if (root["name"]) cfg.name = r.String(root["name"], "name");
  HOVS_REQUIRE(root["camera"], source, "missing 'camera'");
  {
    const YAML::Node c = root["camera"];
    r.OnlyKeys(c, "camera", {"focal_length", "pixel_pitch", "width", "height", "lens_aperture"});
    for (const char* k : {"focal_length", "pixel_pitch", "width", "height", "lens_aperture"})
      HOVS_REQUIRE(c[k], r.Where(c, "camera"), "missing 'camera.", k, "'");
    p.camera.focal_length = r.Number(c["focal_length"], "camera.focal_length");
    p.camera.pixel_pitch = r.Number(c["pixel_pitch"], "camera.pixel_pitch");
    p.camera.width = r.Integer(c["width"], "camera.width");
    p.camera.height = r.Integer(c["height"], "camera.height");
    p.camera.lens_aperture = r.Number(c["lens_aperture"], "camera.lens_aperture");
  }
  ParseLensAndBlur(r, root, &p);
  if (root["mirror"]) {
    const YAML::Node m = root["mirror"];
    r.OnlyKeys(m, "mirror", {"rim_diameter"});
    HOVS_REQUIRE(m["rim_diameter"], r.Where(m, "mirror"), "missing 'mirror.rim_diameter'");
    const double d = r.Number(m["rim_diameter"], "mirror.rim_diameter");
    p.d = {d, d};
  }
  if (root["mounting_height"]) p.mounting_height = r.Number(root["mounting_height"], "mounting_height");
  if (root["long_range_elevation_deg"])
    p.long_range_elevation_deg = r.Number(root["long_range_elevation_deg"], "long_range_elevation_deg");
  if (root["near_ground_radius"]) p.near_ground_radius = r.Number(root["near_ground_radius"], "near_ground_radius");
  if (root["constraints"]) {
    const YAML::Node k = root["constraints"];
    r.OnlyKeys(k, "constraints",
               {"max_upper_elevation_deg", "rim_margin_px", "min_vertical_field_deg", "min_rim_radius_px",
                "max_system_length", "rod_travel", "max_blur_px"});
    Constraints& c = p.constraints;
    if (k["max_upper_elevation_deg"])
      c.max_upper_elevation_deg = r.Number(k["max_upper_elevation_deg"], "constraints.max_upper_elevation_deg");
    if (k["rim_margin_px"]) c.rim_margin_px = r.Number(k["rim_margin_px"], "constraints.rim_margin_px");
    if (k["min_vertical_field_deg"])
      c.min_vertical_field_deg = r.Number(k["min_vertical_field_deg"], "constraints.min_vertical_field_deg");
    if (k["min_rim_radius_px"]) c.min_rim_radius_px = r.Number(k["min_rim_radius_px"], "constraints.min_rim_radius_px");
    if (k["max_system_length"]) c.max_system_length = r.Number(k["max_system_length"], "constraints.max_system_length");
    if (k["max_blur_px"]) p.blur.max_rms_px = r.Positive(k["max_blur_px"], "constraints.max_blur_px");
    if (k["rod_travel"]) {
      HOVS_REQUIRE(k["rod_travel"].IsSequence(), r.Where(k["rod_travel"], "constraints.rod_travel"),
                   "expected [min, max]: the mounting plate's height above the pinhole the rod can set (m)");
      c.rod_travel = RangeOf(r, k["rod_travel"], "constraints.rod_travel");
    }
  }
  if (root["objective"]) {
    const std::string o = r.String(root["objective"], "objective");
    const auto obj = ObjectiveFromString(o);
    HOVS_REQUIRE(obj.has_value(), r.Where(root["objective"], "objective"), "unknown objective '", o,
                 "' (known: ", KnownObjectives(), ")");
    p.objective = *obj;
  }
  if (root["family"]) cfg.family = ParseFamily(r, root["family"]);
  if (root["search"]) {
    const YAML::Node s = root["search"];
    r.OnlyKeys(s, "search", {"a", "b", "d", "grid", "integer_mm"});
    if (s["a"]) p.a = RangeOf(r, s["a"], "search.a");
    if (s["b"]) p.b = RangeOf(r, s["b"], "search.b");
    if (s["d"]) {
      HOVS_REQUIRE(!root["mirror"], r.Where(s["d"], "search.d"),
                   "give the rim diameter either as mirror.rim_diameter (fixed) or as search.d (optimised), not both");
      p.d = RangeOf(r, s["d"], "search.d");
    }
    if (s["grid"]) {
      const YAML::Node g = s["grid"];
      HOVS_REQUIRE(g.IsSequence() && (g.size() == 2 || g.size() == 3), r.Where(g, "search.grid"),
                   "expected [na, nb] or [na, nb, nd]");
      cfg.sweep.na = r.Integer(g[0], "search.grid[0]");
      cfg.sweep.nb = r.Integer(g[1], "search.grid[1]");
      cfg.sweep.nd = g.size() == 3 ? r.Integer(g[2], "search.grid[2]") : 1;
    }
    if (s["integer_mm"]) cfg.integer_mm = r.Bool(s["integer_mm"], "search.integer_mm");
  }
  HOVS_REQUIRE(root["mirror"] || (root["search"] && root["search"]["d"]), source,
               "missing the rim diameter: give mirror.rim_diameter or search.d");
  if (root["marked_design"]) {
    const YAML::Node m = root["marked_design"];
    r.OnlyKeys(m, "marked_design", {"a", "b", "d"});
    HOVS_REQUIRE(m["a"] && m["b"], r.Where(m, "marked_design"), "needs a and b");
    DesignPoint dp{r.Number(m["a"], "marked_design.a"), r.Number(m["b"], "marked_design.b"),
                   m["d"] ? r.Number(m["d"], "marked_design.d") : p.d.min};
    HOVS_REQUIRE(dp.a > 0 && dp.b > 0 && dp.d > 0, r.Where(m, "marked_design"), "a, b and d must be positive");
    cfg.marked = dp;
  }
  if (root["resolution_samples"]) cfg.resolution_samples = r.Integer(root["resolution_samples"], "resolution_samples");
  HOVS_REQUIRE(cfg.resolution_samples >= 2 && cfg.resolution_samples <= 100000, source + " (resolution_samples)",
               "must be in 2..100000");
  if (p.d.Fixed()) cfg.sweep.nd = 1;
  p.Check(source);
  cfg.sweep.Check(source + " (search.grid)");
  return cfg;
}
}  // namespace

DesignConfig ParseDesignConfig(const std::string& text, const std::string& source) {
  return WithYamlErrors(source, [&] { return ParseDesignConfigUnguarded(text, source); });
}

DesignConfig LoadDesignConfig(const std::filesystem::path& path) {
  RequireFile(path, "config file");
  return ParseDesignConfig(ReadFile(path), path.string());
}

}  // namespace hovs::design
