#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/io.h"
#include "design/config.h"
#include "design/family.h"
#include "design/study.h"
#include "results/plot.h"

namespace hovs::apps {

Runner SetupDesign(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string config = "design/reference.yaml";
    std::string out = "results/design";
    std::string shard;
  };
  auto opts = std::make_shared<Options>();
  sub->add_option("-c,--config", opts->config,
                  "design config (YAML); a config with a family list designs a turret's mirrors")
      ->capture_default_str();
  sub->add_option("-o,--out", opts->out, "report folder (replaced atomically)")->capture_default_str();
  sub->add_option("--shard", opts->shard,
                  "I/N: rows of the sweep for shard I (from 0) of N, no report (hovs merge joins the shards and "
                  "writes it); default: from SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT when Slurm sets them");
  return [opts, global]() {
    const design::DesignConfig cfg = design::LoadDesignConfig(opts->config);
    int shard = 0, shards = 1;
    ParseShard(opts->shard, &shard, &shards);
    if (shards > 1) {
      design::WriteDesignShard(cfg, shard, shards, opts->out, design::DesignVersions());
      if (!global->quiet)
        std::cout << "hovs design: sweep shard " << shard << " of " << shards << " -> " << opts->out
                  << "/design-shard.json\n";
      return 0;
    }
    HOVS_REQUIRE(results::CanRender(), "hovs design",
                 "figures need an X display and DISPLAY is unset; run under `xvfb-run -a`");
    std::string summary, json_file;
    if (cfg.family.empty()) {
      summary = design::WriteDesignReport(cfg, design::RunDesignStudy(cfg), opts->out);
      json_file = "design.json";
    } else {
      summary = design::WriteFamilyReport(cfg, design::RunFamilyStudy(cfg), opts->out);
      json_file = "family.json";
    }
    if (global->json)
      std::cout << ReadFile(std::filesystem::path(opts->out) / json_file);
    else if (!global->quiet)
      std::cout << summary;
    return 0;
  };
}

Runner SetupVersion(CLI::App*, const GlobalOptions*) {
  return []() {
    for (const auto& [k, v] : Versions()) std::cout << k << ": " << v << "\n";
    return 0;
  };
}

}  // namespace hovs::apps
