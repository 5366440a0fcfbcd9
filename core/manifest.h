// The dataset manifest (dataset.json): one format for rendered sets and real captures. Read and checked once
// here, so that every command (calibrate, unwrap, stereo-calibrate, depth, position, live, capture replay) meets
// a malformed manifest as one error naming the file and the field, not as a JSON exception.
//
// Structure checked (every key must be one a hovs writer puts there; unknown keys are refused by name):
//   format    "hovs-dataset"
//   version   1
//   units     [ {name: string, ...}, ... ]              names non-empty and unique
//   frames    [ {id: integer >= 0 (unique),
//                views: [ {unit: string, image: string,  unit one of the units' names, one view per unit
//                          ground_truth?: {exr?: string, sidecar: string},  (absent for real captures; exr
//                                                                            absent without per-pixel channels)
//                          device_ns?: unsigned integer, width?, height?: 1..65535, ...}, ... ]}, ... ]
// Paths in views are relative to the manifest's folder and stay inside it (no absolute paths, no ".."): a
// shared dataset cannot make hovs open files elsewhere.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace hovs {

inline constexpr int kManifestVersion = 1;

// Parses and checks the manifest at path; throws hovs::Error naming the file and the offending field.
nlohmann::json LoadDatasetManifest(const std::filesystem::path& path);

// The same checks on a manifest already parsed (`source` names it in errors).
void CheckDatasetManifest(const nlohmann::json& m, const std::string& source);

// A path of a checked manifest (a view's image, EXR or sidecar) as a path to open: relative to its folder.
std::filesystem::path ManifestPath(const std::filesystem::path& manifest, const nlohmann::json& relative);

}  // namespace hovs
