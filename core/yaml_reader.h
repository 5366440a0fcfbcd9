// Validating access to YAML config files: every error names the file, the line and the key, unknown keys are
// rejected with the list of known ones, numbers must be finite.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <set>
#include <string>

#include "core/error.h"
#include "core/lens.h"
#include "core/types.h"

namespace hovs {

// Runs a parse of YAML text read from `source`: yaml-cpp's own exceptions (a sequence indexed as a map, a
// conversion it refuses) become hovs::Error naming the source, like every other error of the parse.
template <class F>
auto WithYamlErrors(const std::string& source, F&& parse) -> decltype(parse()) {
  try {
    return parse();
  } catch (const YAML::Exception& e) { throw Error(source, std::string("malformed YAML: ") + e.what()); }
}

class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  // Parses text; throws hovs::Error with the line of a syntax error.
  YAML::Node Load(const std::string& text) const;

  // "file:line (key)"
  std::string Where(const YAML::Node& n, const std::string& key) const;
  void OnlyKeys(const YAML::Node& map, const std::string& path, const std::set<std::string>& known) const;
  const YAML::Node& Require(const YAML::Node& map, const std::string& path, const std::string& key,
                            YAML::Node* out) const;

  // Throws hovs::Error naming the key when n is absent (an invalid or null node): every accessor below checks
  // this first, so a missing key is named instead of reaching yaml-cpp's own "invalid node" exception.
  void Present(const YAML::Node& n, const std::string& key) const;
  double Number(const YAML::Node& n, const std::string& key) const;
  double Positive(const YAML::Node& n, const std::string& key) const;
  int Integer(const YAML::Node& n, const std::string& key) const;
  // A seed: an integer in [0, 2^53] (negative values would wrap to 2^64 - 1).
  uint64_t Seed(const YAML::Node& n, const std::string& key) const;
  // A name that becomes part of file names: letters, digits, '_', '-' and '.', not starting with '.', 1 to 64.
  std::string Name(const YAML::Node& n, const std::string& key) const;
  bool Bool(const YAML::Node& n, const std::string& key) const;
  std::string String(const YAML::Node& n, const std::string& key) const;
  Vec3d Vector3(const YAML::Node& n, const std::string& key) const;
  std::array<float, 3> Colour(const YAML::Node& n, const std::string& key) const;  // [r, g, b] in [0, 1]

  // A distance that may be "infinity" (or "inf"): a positive number otherwise.
  double DistanceOrInfinity(const YAML::Node& n, const std::string& key) const;
  // A lens block {f_number | aperture_diameter, focus_distance, wavelength} (core/lens.h) of a lens of the given
  // focal length, each key optional (defaults: f/4, focused at infinity, 550 nm), checked (ThinLens::Check).
  ThinLens Lens(const YAML::Node& n, const std::string& key, double focal_length) const;

  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

}  // namespace hovs
