// Mirror design configurations (YAML).
#include "design/config.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) { hovs::design::ParseDesignConfig(input, "design.yaml"); }

}  // namespace

HOVS_FUZZ_TARGET(Run)
