// hovs export: a rendered dataset in a layout learning pipelines read (depth/learning_export.h).
//
//   hovs export --dataset D/dataset.json --to equirect [--width 1024] --out E
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "core/error.h"
#include "core/io.h"
#include "depth/learning_export.h"

namespace hovs::apps {

Runner SetupExport(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string dataset, to = "equirect", out = "results/export";
    int width = 1024;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--dataset", o->dataset, "a rendered dataset's manifest (dataset.json)")->required();
  sub->add_option("--to", o->to, "equirect: equirectangular RGB, range and mask per frame and unit, and the poses")
      ->capture_default_str();
  AddBounded(sub, "--width", &o->width, "equirectangular width in pixels (height: width / 2)", 16, 16384);
  sub->add_option("-o,--out", o->out, "output folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    HOVS_REQUIRE(o->to == "equirect", "--to", "expected equirect (got '", o->to, "')");
    depth::EquirectOptions options;
    options.width = o->width;
    options.progress = !global->quiet;
    options.Check("--width");
    StagedDirectory stage(o->out, "export", {o->dataset});
    const depth::EquirectExport e =
        depth::ExportEquirect(o->dataset, options, stage.staging(), nlohmann::json(Versions()));
    stage.Commit();
    if (!global->quiet)
      std::printf("hovs export: %d frames x %d units -> %s (equirectangular %d x %d, %.1f %% of pixels valid)\n",
                  e.frames, e.units, o->out.c_str(), o->width, o->width / 2, 100 * e.valid_fraction);
    return 0;
  };
}

}  // namespace hovs::apps
