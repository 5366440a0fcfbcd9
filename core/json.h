// JSON files that hovs reads (manifests, sidecars, calibrations, stereo results, mapping headers): parsed strictly.
// A key that appears twice in one object is an error (nlohmann's parser would keep the last one silently), as is
// nesting deeper than 256; a syntax error names the line and column.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hovs {

// Throws hovs::Error(where, ...) on a syntax error, a duplicate key or too deep a nesting.
nlohmann::json ParseJson(const std::string& text, const std::string& where);

// ReadFile (core/io.h) and ParseJson, the file naming the errors.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace hovs
