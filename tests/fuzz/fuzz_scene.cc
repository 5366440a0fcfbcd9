// Scene YAML (units, objects, textures, render settings), with every check of a scene file (units clear of the
// objects, a depth sequence's poses).
#include "scenes/scene_config.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) { hovs::scenes::ParseSceneConfig(input, "scene.yaml", "."); }

}  // namespace

HOVS_FUZZ_TARGET(Run)
