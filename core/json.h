// JSON files that hovs reads (manifests, sidecars, calibrations, stereo results, mapping headers): parsed strictly.
// A key that appears twice in one object is an error (nlohmann's parser would keep the last one silently), as is
// nesting deeper than 256; a syntax error names the line and column.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace hovs {

// Throws hovs::Error(where, ...) on a syntax error, a duplicate key or too deep a nesting.
nlohmann::json ParseJson(const std::string& text, const std::string& where);

// ReadFile (core/io.h) and ParseJson, the file naming the errors.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

// Checked reads of a parsed file's fields. nlohmann's own conversions throw type errors on the wrong type, and
// from a float to an int are undefined (6.7e79 read as a width); these name `where` and the key instead.
// The string at j[key], or "" when j is not an object or the field is absent or not a string (no throw).
std::string JsonText(const nlohmann::json& j, const char* key);
// The string at j[key]; throws hovs::Error when absent or not a string.
std::string JsonString(const nlohmann::json& j, const char* key, const std::string& where);
// A finite number at j[key]; throws hovs::Error when absent, not a number or not finite.
double JsonNumber(const nlohmann::json& j, const char* key, const std::string& where);
// A whole number in [lo, hi] at j[key] (an integer, or a float without a fraction).
int64_t JsonInteger(const nlohmann::json& j, const char* key, int64_t lo, int64_t hi, const std::string& where);
// A list of finite numbers at j[key], with between min_size and max_size entries.
std::vector<double> JsonNumbers(const nlohmann::json& j, const char* key, size_t min_size, size_t max_size,
                                const std::string& where);

}  // namespace hovs
