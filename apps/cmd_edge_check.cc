#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/io.h"
#include "design/config.h"
#include "design/study.h"
#include "study/edge_check.h"

namespace hovs::apps {

Runner SetupEdgeCheck(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string config = "design/reference.yaml";
    std::string out = "results/edge-check";
    std::vector<double> mirror, elevations, distances = {1.0, 5.0, 50.0};
    double f_number = 0, focus = 0;
    int samples = 400, region = 48;
    uint64_t seed = 1;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("-c,--config", o->config, "design config (YAML): its camera and lens")->capture_default_str();
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  sub->add_option("--mirror", o->mirror, "a b [d] (m): the mirror; default: the config's marked design")
      ->expected(2, 3)
      ->check(Bounded(1e-3, 1.0));
  AddBounded(sub, "--f-number", &o->f_number, "f-number (0: the config's lens)", 0, 1000);
  AddBounded(sub, "--focus", &o->focus,
             "focus distance from the lens, m (0: the config's; at infinity: the best single focus)", 0, 1e6);
  sub->add_option("--elevations", o->elevations, "elevations (deg); default: 5 evenly inside the field")
      ->check(Bounded(-89.9, 89.9));
  sub->add_option("--distances", o->distances, "scene distances from F1 (m)")
      ->check(Bounded(0.2, 1000, true))
      ->capture_default_str();
  AddBounded(sub, "--samples", &o->samples, "samples per pixel (a square is stratified)", 16, 65536);
  AddBounded(sub, "--region", &o->region, "px, the square rendered on each edge", 24, 512);
  AddBounded(sub, "--seed", &o->seed, "sample seed", 0, 9007199254740992.0);
  return [o, global]() {
    const design::DesignConfig cfg = design::LoadDesignConfig(o->config);
    study::EdgeCheckOptions eo;
    eo.camera = cfg.problem.camera;
    if (!o->mirror.empty())
      eo.mirror = {o->mirror[0], o->mirror[1], o->mirror.size() > 2 ? o->mirror[2] : cfg.problem.d.min};
    else if (cfg.marked)
      eo.mirror = *cfg.marked;
    else
      throw Error(o->config, "has no marked_design: give the mirror with --mirror a b [d]");
    if (o->f_number > 0) eo.camera.lens.f_number = o->f_number;
    if (o->focus > 0) eo.camera.lens.focus_distance = o->focus;
    eo.elevations_deg = o->elevations, eo.distances = o->distances;
    eo.samples = o->samples, eo.region = o->region, eo.seed = o->seed;
    const study::EdgeCheck check = study::RunEdgeCheck(eo);
    const std::string summary = study::WriteEdgeCheck(check, o->out, design::DesignVersions());
    if (global->json)
      std::cout << ReadFile(std::filesystem::path(o->out) / "edge_check.json");
    else if (!global->quiet)
      std::cout << summary;
    return 0;  // a measurement, like hovs tolerance: edges out of tolerance are marked NOT MET in the summary
  };
}

}  // namespace hovs::apps
