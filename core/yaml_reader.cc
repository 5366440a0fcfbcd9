#include "core/yaml_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/error.h"

namespace hovs {

YAML::Node YamlReader::Load(const std::string& text) const {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw Error(source_ + ":" + std::to_string(e.mark.line + 1), "not valid YAML: " + e.msg);
  }
}

std::string YamlReader::Where(const YAML::Node& n, const std::string& key) const {
  std::string w = source_;
  if (n.IsDefined() && n.Mark().line >= 0) w += ":" + std::to_string(n.Mark().line + 1);
  return key.empty() ? w : w + " (" + key + ")";
}

void YamlReader::OnlyKeys(const YAML::Node& map, const std::string& path, const std::set<std::string>& known) const {
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
  HOVS_REQUIRE(map.IsMap(), Where(map, path), "expected a mapping with '", key, "'");
  *out = map[key];
  HOVS_REQUIRE(out->IsDefined() && !out->IsNull(), Where(map, path), "missing '", path.empty() ? key : path + "." + key,
               "'");
  return *out;
}

double YamlReader::Number(const YAML::Node& n, const std::string& key) const {
  HOVS_REQUIRE(n.IsScalar(), Where(n, key), "expected a number");
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) { throw Error(Where(n, key), "expected a number, got '" + n.Scalar() + "'"); }
  HOVS_REQUIRE(std::isfinite(v), Where(n, key), "must be a finite number (got ", n.Scalar(), ")");
  return v;
}

double YamlReader::Positive(const YAML::Node& n, const std::string& key) const {
  const double v = Number(n, key);
  HOVS_REQUIRE(v > 0, Where(n, key), "must be positive (got ", v, ")");
  return v;
}

int YamlReader::Integer(const YAML::Node& n, const std::string& key) const {
  const double v = Number(n, key);
  HOVS_REQUIRE(v == std::floor(v) && std::abs(v) < 1e9, Where(n, key), "expected an integer, got ", n.Scalar());
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
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) { throw Error(Where(n, key), "expected true or false"); }
}

std::string YamlReader::String(const YAML::Node& n, const std::string& key) const {
  HOVS_REQUIRE(n.IsScalar(), Where(n, key), "expected a string");
  return n.as<std::string>();
}

Vec3d YamlReader::Vector3(const YAML::Node& n, const std::string& key) const {
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
