// Turret machine files (YAML) with every check of the machine's geometry (rig/turret.h); the surroundings scene
// is looked up in scenes/ (scripts/fuzz.sh runs from the source tree).
#include "rig/turret.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) { hovs::rig::ParseTurretSpec(input, "machine.yaml", "scenes"); }

}  // namespace

HOVS_FUZZ_TARGET(Run)
