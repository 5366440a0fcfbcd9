#include "core/json.h"

#include <cmath>
#include <set>
#include <vector>

#include "core/error.h"
#include "core/io.h"

namespace hovs {

nlohmann::json ParseJson(const std::string& text, const std::string& where) {
  constexpr int kMaxDepth = 256;
  std::vector<std::set<std::string>> keys;  // one set per open object
  std::string duplicate;
  int too_deep = 0;
  const nlohmann::json::parser_callback_t check = [&](int depth, nlohmann::json::parse_event_t event,
                                                      nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (depth > kMaxDepth) too_deep = depth;
    if (event == E::object_start) keys.emplace_back();
    if (event == E::object_end && !keys.empty()) keys.pop_back();
    if (event == E::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
      duplicate = parsed.get<std::string>();
    return true;
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text, check);
  } catch (const nlohmann::json::parse_error& e) {
    // The line and column of the byte the parser stopped at.
    size_t line = 1, column = 1;
    for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n')
        ++line, column = 1;
      else
        ++column;
    }
    std::string what = e.what();
    const size_t colon = what.rfind(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw Error(where,
                "not valid JSON at line " + std::to_string(line) + ", column " + std::to_string(column) + ": " + what);
  } catch (const nlohmann::json::exception& e) {  // a number out of range (1e999), ...
    std::string what = e.what();
    const size_t bracket = what.find("] ");
    throw Error(where, "not valid JSON: " + (bracket == std::string::npos ? what : what.substr(bracket + 2)));
  }
  HOVS_REQUIRE(duplicate.empty(), where, "the key '", duplicate, "' appears twice in one object");
  HOVS_REQUIRE(too_deep == 0, where, "nested deeper than ", kMaxDepth, " levels");
  return j;
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path) { return ParseJson(ReadFile(path), path.string()); }

std::string JsonText(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return "";
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

namespace {
double FiniteNumber(const nlohmann::json& v, const std::string& where) {
  HOVS_REQUIRE(v.is_number(), where, "expected a number (got ", v.type_name(), ")");
  const double x = v.get<double>();
  HOVS_REQUIRE(std::isfinite(x), where, "expected a finite number");
  return x;
}
}  // namespace

std::string JsonString(const nlohmann::json& j, const char* key, const std::string& where) {
  HOVS_REQUIRE(j.is_object() && j.contains(key) && j[key].is_string(), where + " (" + key + ")",
               "missing or not a string");
  return j[key].get<std::string>();
}

double JsonNumber(const nlohmann::json& j, const char* key, const std::string& where) {
  HOVS_REQUIRE(j.is_object() && j.contains(key), where, "missing '", key, "'");
  return FiniteNumber(j[key], where + "." + key);
}

int64_t JsonInteger(const nlohmann::json& j, const char* key, int64_t lo, int64_t hi, const std::string& where) {
  const double x = JsonNumber(j, key, where);
  HOVS_REQUIRE(x == std::floor(x) && x >= double(lo) && x <= double(hi), where + "." + key,
               "expected a whole number in ", lo, "..", hi, " (got ", j[key].dump(), ")");
  return static_cast<int64_t>(x);
}

std::vector<double> JsonNumbers(const nlohmann::json& j, const char* key, size_t min_size, size_t max_size,
                                const std::string& where) {
  HOVS_REQUIRE(j.is_object() && j.contains(key), where, "missing '", key, "'");
  const auto& a = j[key];
  HOVS_REQUIRE(a.is_array() && a.size() >= min_size && a.size() <= max_size, where + "." + key, "expected a list of ",
               min_size, " to ", max_size, " numbers");
  std::vector<double> v;
  for (size_t k = 0; k < a.size(); ++k)
    v.push_back(FiniteNumber(a[k], where + "." + key + "[" + std::to_string(k) + "]"));
  return v;
}

}  // namespace hovs
