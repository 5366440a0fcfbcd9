#include "apps/commands.h"

#include <iostream>

#include "calib/checkerboard_detector.h"
#include "core/error.h"
#include "core/version.h"
#include "design/study.h"
#include "hw/camera_source.h"
#include "raytrace/render.h"

namespace hovs::apps {

std::map<std::string, std::string> Versions() {
  auto v = design::DesignVersions();
  for (const auto& more : {raytrace::RaytraceVersions(), calib::CalibVersions(), hw::HwVersions()})
    v.insert(more.begin(), more.end());
  return v;
}

const std::vector<Command>& Commands() {
  static const std::vector<Command> table = {
      {"design", "Mirror design study: sweep (a, b[, d]), constrained optima, report with figures", SetupDesign},
      {"render", "Render a scene through its catadioptric units, with ground truth (EXR + JSON)", SetupRender},
      {"dataset", "Render a dataset (a monocular calibration set) with ground truth and a manifest", SetupDataset},
      {"calibrate", "Monocular calibration (polynomial and unified models) from a corner table or a dataset", SetupCalibrate},
      {"unwrap", "Virtual perspective views and panoramas from catadioptric images (any model), mapping files", SetupUnwrap},
      {"stereo-calibrate", "Relative pose of two units from ArUco board pairs (detection in unwrapped views, joint solve)", SetupStereoCalibrate},
      {"depth", "Dense and sparse binocular depth of a two-unit dataset (rectification, SGBM, point clouds)", SetupDepth},
      {"capture", "Capture frames from GigE Vision cameras (Aravis), a replay or the GigE Vision simulator into a dataset", SetupCapture},
      {"position", "Visual positioning: the camera's offset from the mirror design, from the rim in one image", SetupPosition},
      {"live", "Live expansion: camera (or simulator, replay) frames into views, raw Bayer to RGB, with latency figures", SetupLive},
      {"validate", "End to end against ground truth: design, renders, detection, calibration, stereo, views, depth; report", SetupValidate},
      {"version", "Print the versions of hovs and its libraries", SetupVersion},
  };
  return table;
}

int RunCommandLine(int argc, const char* const* argv, bool rethrow) {
  CLI::App app{"hovs: design, render, calibrate, unwrap and measure hyperboloid catadioptric vision systems"};
  app.set_version_flag("--version", HovsVersion());
  GlobalOptions global;
  app.add_flag("-q,--quiet", global.quiet, "print nothing but errors");
  app.add_flag("--json", global.json, "print the machine-readable result on stdout");
  app.require_subcommand(1, 1);
  std::vector<std::pair<CLI::App*, Runner>> runners;
  for (const auto& cmd : Commands()) {
    CLI::App* sub = app.add_subcommand(cmd.name, cmd.help);
    runners.emplace_back(sub, cmd.setup(sub, &global));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (rethrow) throw Error("command line", std::string(e.what()));
    if (e.get_exit_code() == 0) return app.exit(e);   // --help, --version: CLI11's own output
    // Any other command-line error is bad input like the rest: one line, exit 2.
    std::cerr << "hovs: error: " << e.what() << " (see --help)\n";
    return 2;
  }
  for (auto& [sub, run] : runners) {
    if (!sub->parsed()) continue;
    if (rethrow) return run();
    try {
      return run();
    } catch (const Error& e) {
      std::cerr << "hovs " << sub->get_name() << ": error: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "hovs " << sub->get_name() << ": internal error: " << e.what() << "\n";
      return 3;
    }
  }
  return 1;
}

int RunCommandLine(const std::vector<std::string>& args, bool rethrow) {
  std::vector<const char*> argv = {"hovs"};
  for (const auto& a : args) argv.push_back(a.c_str());
  return RunCommandLine(static_cast<int>(argv.size()), argv.data(), rethrow);
}

}  // namespace hovs::apps
