// The dataset manifest (dataset.json): one format for rendered sets and real captures. Read and checked once
// here, so that every command (calibrate, unwrap, stereo-calibrate, depth, position, live, capture replay) meets
// a malformed manifest as one error naming the file and the field, not as a JSON exception.
//
// Structure checked (other keys are free):
//   format    "hovs-dataset"
//   units     [ {name: string, ...}, ... ]              names unique
//   frames    [ {views: [ {unit: string, image: string,  unit one of the units' names
//                          ground_truth?: {exr: string, sidecar: string},   (absent for real captures)
//                          device_ns?: unsigned integer}, ... ]}, ... ]
// Paths in views are relative to the manifest's folder.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace hovs {

// Parses and checks the manifest at path; throws hovs::Error naming the file and the offending field.
nlohmann::json LoadDatasetManifest(const std::filesystem::path& path);

// The same checks on a manifest already parsed (`source` names it in errors).
void CheckDatasetManifest(const nlohmann::json& m, const std::string& source);

}  // namespace hovs
