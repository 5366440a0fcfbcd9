// Dataset manifests (dataset.json) and frame sidecars: the input is parsed as JSON and checked as a manifest,
// its units read as the commands read them; an object with "boards" is read as a sidecar too.
#include "core/json.h"
#include "core/manifest.h"
#include "scenes/ground_truth.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  const nlohmann::json j = hovs::ParseJson(input, "dataset.json");
  if (j.is_object() && j.contains("boards") && !j.contains("frames")) {
    hovs::scenes::VisibleSidecarCorners(j, "sidecar.json");
    return;
  }
  hovs::CheckDatasetManifest(j, "dataset.json");
  for (size_t i = 0; i < j["units"].size(); ++i)
    if (j["units"][i].contains("mirror")) {
      try {
        hovs::scenes::UnitFromJson(j["units"][i], "dataset.json (units)");
      } catch (const hovs::Error&) {}
    }
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
