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
  };
  auto opts = std::make_shared<Options>();
  sub->add_option("-c,--config", opts->config,
                  "design config (YAML); a config with a family list designs a turret's mirrors")
      ->capture_default_str();
  sub->add_option("-o,--out", opts->out, "report folder (replaced atomically)")->capture_default_str();
  return [opts, global]() {
    const design::DesignConfig cfg = design::LoadDesignConfig(opts->config);
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
