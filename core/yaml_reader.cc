#include "core/yaml_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/error.h"

namespace hovs {

namespace {
// A key given twice in one mapping: yaml-cpp keeps both pairs and a lookup finds one of them, so the file would
// silently mean something else than it says. Checked over the whole document (at most 64 levels deep).
void RefuseDuplicateKeys(const YamlReader& r, const YAML::Node& n, const std::string& path, int depth) {
  HOVS_REQUIRE(depth <= 64, r.Where(n, path), "nested deeper than 64 levels");
  if (n.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : n) {
      const std::string k = kv.first.IsScalar() ? kv.first.Scalar() : "";
      const std::string key = path.empty() ? k : path + "." + k;
      HOVS_REQUIRE(!kv.first.IsScalar() || seen.insert(k).second, r.Where(kv.first, key), "duplicate key '", k,
                   "' (given twice; give it once)");
      RefuseDuplicateKeys(r, kv.second, key, depth + 1);
    }
  } else if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i) RefuseDuplicateKeys(r, n[i], path + "[" + std::to_string(i) + "]", depth + 1);
  }
}
}  // namespace

YAML::Node YamlReader::Load(const std::string& text) const {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw Error(source_ + ":" + std::to_string(e.mark.line + 1), "not valid YAML: " + e.msg);
  }
  RefuseDuplicateKeys(*this, root, "", 0);
  return root;
}

std::string YamlReader::Where(const YAML::Node& n, const std::string& key) const {
  std::string w = source_;
  if (n.IsDefined() && n.Mark().line >= 0) w += ":" + std::to_string(n.Mark().line + 1);
  return key.empty() ? w : w + " (" + key + ")";
}

void YamlReader::OnlyKeys(const YAML::Node& map, const std::string& path, const std::set<std::string>& known) const {
  Present(map, path);
  HOVS_REQUIRE(map.IsMap(), Where(map, path), "expected a mapping");
  std::set<std::string> seen;
  for (const auto& kv : map) {
    const std::string k = kv.first.as<std::string>();
    HOVS_REQUIRE(seen.insert(k).second, Where(kv.first, path.empty() ? k : path + "." + k), "duplicate key '", k, "'");
    if (known.count(k)) continue;
    std::string list;
    for (const auto& s : known) list += (list.empty() ? "" : ", ") + s;
    throw Error(Where(kv.first, path.empty() ? k : path + "." + k),
                "unknown key '" + k + "'" + (path.empty() ? "" : " in '" + path + "'") + " (known: " + list + ")");
  }
}

const YAML::Node& YamlReader::Require(const YAML::Node& map, const std::string& path, const std::string& key,
                                      YAML::Node* out) const {
  const std::string name = path.empty() ? key : path + "." + key;
  HOVS_REQUIRE(map.IsDefined() && map.IsMap(), Where(map, path), "expected a mapping with '", name, "'");
  // Looked up without touching the node first: a const lookup of an absent key is an invalid node, which
  // yaml-cpp refuses to assign ("invalid node; this may result from using a map iterator...").
  const YAML::Node found = static_cast<const YAML::Node&>(map)[key];
  HOVS_REQUIRE(found.IsDefined() && !found.IsNull(), Where(map, path), "missing '", name, "'");
  out->reset(found);
  return *out;
}

void YamlReader::Present(const YAML::Node& n, const std::string& key) const {
  HOVS_REQUIRE(n.IsDefined() && !n.IsNull(), source_ + " (" + key + ")", "missing '", key, "'");
}

double YamlReader::Number(const YAML::Node& n, const std::string& key) const {
  Present(n, key);
  HOVS_REQUIRE(n.IsScalar(), Where(n, key), "expected a number");
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) { throw Error(Where(n, key), "expected a number, got '" + n.Scalar() + "'"); }
  HOVS_REQUIRE(std::isfinite(v), Where(n, key), "must be a finite number (got ", n.Scalar(), ")");
  return v;
}

double YamlReader::DistanceOrInfinity(const YAML::Node& n, const std::string& key) const {
  Present(n, key);
  if (n.IsScalar() && (n.Scalar() == "infinity" || n.Scalar() == "inf")) return HUGE_VAL;
  const double v = Number(n, key);
  HOVS_REQUIRE(v > 0, Where(n, key), "must be a positive distance in metres or 'infinity' (got ", v, ")");
  return v;
}

ThinLens YamlReader::Lens(const YAML::Node& n, const std::string& key, double focal_length) const {
  Present(n, key);
  HOVS_REQUIRE(n.IsMap(), Where(n, key),
               "expected a mapping {f_number or aperture_diameter, focus_distance, wavelength}");
  OnlyKeys(n, key, {"f_number", "aperture_diameter", "focus_distance", "wavelength"});
  HOVS_REQUIRE(!(n["f_number"] && n["aperture_diameter"]), Where(n, key),
               "give the aperture as f_number or as aperture_diameter, not both");
  ThinLens lens;
  lens.focal_length = focal_length;
  if (n["f_number"]) lens.f_number = Number(n["f_number"], key + ".f_number");
  if (n["aperture_diameter"]) {
    const double diameter = Positive(n["aperture_diameter"], key + ".aperture_diameter");
    HOVS_REQUIRE(diameter <= 2 * focal_length, Where(n["aperture_diameter"], key + ".aperture_diameter"),
                 "must be at most twice the focal length, f/0.5 (got ", diameter, " m for f = ", focal_length, " m)");
    lens.f_number = focal_length / diameter;
  }
  if (n["focus_distance"]) lens.focus_distance = DistanceOrInfinity(n["focus_distance"], key + ".focus_distance");
  if (n["wavelength"]) lens.wavelength = Number(n["wavelength"], key + ".wavelength");
  lens.Check(Where(n, key));
  return lens;
}

double YamlReader::Positive(const YAML::Node& n, const std::string& key) const {
  const double v = Number(n, key);
  HOVS_REQUIRE(v > 0, Where(n, key), "must be positive (got ", v, ")");
  return v;
}

int YamlReader::Integer(const YAML::Node& n, const std::string& key) const {
  const double v = Number(n, key);
  HOVS_REQUIRE(v == std::floor(v), Where(n, key), "expected an integer, got ", n.Scalar());
  HOVS_REQUIRE(std::abs(v) < 1e9, Where(n, key), "expected an integer of magnitude below 1000000000, got ", n.Scalar());
  return static_cast<int>(v);
}

uint64_t YamlReader::Seed(const YAML::Node& n, const std::string& key) const {
  const double v = Number(n, key);
  HOVS_REQUIRE(v == std::floor(v) && v >= 0 && v <= 9007199254740992.0, Where(n, key),
               "a seed must be an integer in [0, 2^53] (got ", n.Scalar(), ")");
  return static_cast<uint64_t>(v);
}

std::string YamlReader::Name(const YAML::Node& n, const std::string& key) const {
  const std::string s = String(n, key);
  const bool chars = std::all_of(s.begin(), s.end(),
                                 [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-' || c == '.'; });
  HOVS_REQUIRE(!s.empty() && s.size() <= 64 && chars && s[0] != '.', Where(n, key), "'", s,
               "' is not a usable name (1 to 64 letters, digits, '_', '-' or '.', not starting with '.': it becomes "
               "part of file names)");
  return s;
}

bool YamlReader::Bool(const YAML::Node& n, const std::string& key) const {
  Present(n, key);
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) { throw Error(Where(n, key), "expected true or false"); }
}

std::string YamlReader::String(const YAML::Node& n, const std::string& key) const {
  Present(n, key);
  HOVS_REQUIRE(n.IsScalar(), Where(n, key), "expected a string");
  return n.as<std::string>();
}

Vec3d YamlReader::Vector3(const YAML::Node& n, const std::string& key) const {
  Present(n, key);
  HOVS_REQUIRE(n.IsSequence() && n.size() == 3, Where(n, key), "expected [x, y, z]");
  return Vec3d(Number(n[0], key + "[0]"), Number(n[1], key + "[1]"), Number(n[2], key + "[2]"));
}

std::array<float, 3> YamlReader::Colour(const YAML::Node& n, const std::string& key) const {
  const Vec3d c = Vector3(n, key);
  for (int i = 0; i < 3; ++i)
    HOVS_REQUIRE(c(i) >= 0 && c(i) <= 1, Where(n, key), "colour components must be in [0, 1]");
  return {static_cast<float>(c(0)), static_cast<float>(c(1)), static_cast<float>(c(2))};
}

}  // namespace hovs
