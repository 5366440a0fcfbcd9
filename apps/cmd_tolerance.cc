// hovs tolerance: the Monte-Carlo tolerance study of a design (study/tolerance.h), whole or one shard.
#include <chrono>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "design/config.h"
#include "study/tolerance.h"

namespace hovs::apps {

Runner SetupTolerance(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string config = "study/reference.yaml";
    std::string design, shard, out = "results/tolerance";
    long long samples = 1000;
    long long seed = -1;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("-c,--config", o->config, "tolerance config (YAML): the design, the tolerances, the limits")
      ->capture_default_str();
  sub->add_option("--design", o->design, "design config whose marked design is the nominal (overrides the config's)");
  AddBounded(sub, "-n,--samples", &o->samples, "Monte-Carlo samples", 1, 10000000);
  sub->add_option("--seed", o->seed, "seed of the draws (overrides the config)")->check(Bounded(0, 9007199254740992.0));
  sub->add_option("--shard", o->shard,
                  "I/N: samples of shard I (from 0) of N (hovs merge joins them); default: from SLURM_ARRAY_TASK_ID "
                  "and SLURM_ARRAY_TASK_COUNT when Slurm sets them");
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    std::optional<design::DesignConfig> design;
    if (!o->design.empty()) design = design::LoadDesignConfig(o->design);
    study::ToleranceConfig config = study::LoadToleranceConfig(o->config, design ? &*design : nullptr);
    if (o->seed >= 0) config.seed = static_cast<uint64_t>(o->seed);
    int shard = 0, shards = 1;
    ParseShard(o->shard, &shard, &shards);
    HOVS_REQUIRE(shards <= o->samples, "--shard", "more shards (", shards, ") than samples (", o->samples, ")");
    const auto start = std::chrono::steady_clock::now();
    const auto warnings =
        study::WriteToleranceStudy(config, o->samples, shard, shards, o->out, Versions(), !global->quiet);
    for (const auto& w : warnings) std::cerr << "hovs tolerance: warning: " << w << "\n";
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (global->json) {
      std::cout << ReadFile(std::filesystem::path(o->out) / "tolerance.json");
    } else if (!global->quiet) {
      std::cout << "hovs tolerance: " << o->samples << " samples"
                << (shards > 1 ? " (shard " + std::to_string(shard) + " of " + std::to_string(shards) + ")"
                               : std::string())
                << " in " << FormatNumber("%.1f", seconds) << " s -> " << o->out << "/tolerance.json\n";
    }
    return 0;
  };
}

}  // namespace hovs::apps
