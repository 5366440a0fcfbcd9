// View layouts (YAML), with the memory check of their views.
#include "core/large_pages.h"
#include "tests/fuzz/fuzz_common.h"
#include "unwrap/layout.h"

namespace {

void Run(const std::string& input) {
  const auto layout = hovs::unwrap::ParseLayout(input, "layout.yaml", "layout");
  hovs::unwrap::CheckViewsMemory("layout.yaml", layout.views, hovs::AvailableMemoryBytes());
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
