// Tolerance study configs (YAML) against the reference design, each accepted config's first sample drawn and
// evaluated (a tolerance the checks let through must evaluate to figures or to failed ones, never crash).
#include "design/config.h"
#include "study/tolerance.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  static const hovs::design::DesignConfig design = hovs::design::LoadDesignConfig("design/reference.yaml");
  const hovs::study::ToleranceConfig c = hovs::study::ParseToleranceConfig(input, "tolerance.yaml", "study", &design);
  const hovs::study::ToleranceEvaluator ev(c);
  ev.Evaluate(hovs::study::DrawErrors(c, 0, 0), hovs::study::DrawErrors(c, 0, 1));
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
