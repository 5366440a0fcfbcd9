// hovs: one command, subcommands from the table in commands.cc.
#include <glog/logging.h>

#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/version.h"

int main(int argc, char** argv) {
  // Ceres logs through glog; hovs reports what matters itself.
  FLAGS_minloglevel = 3;
  google::InitGoogleLogging(argv[0]);
  CLI::App app{"hovs: design, render, calibrate, unwrap and measure hyperboloid catadioptric vision systems"};
  app.set_version_flag("--version", hovs::HovsVersion());
  hovs::apps::GlobalOptions global;
  app.add_flag("-q,--quiet", global.quiet, "print nothing but errors");
  app.add_flag("--json", global.json, "print the machine-readable result on stdout");
  app.require_subcommand(1, 1);
  std::vector<std::pair<CLI::App*, hovs::apps::Runner>> runners;
  for (const auto& cmd : hovs::apps::Commands()) {
    CLI::App* sub = app.add_subcommand(cmd.name, cmd.help);
    runners.emplace_back(sub, cmd.setup(sub, &global));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  for (auto& [sub, run] : runners) {
    if (!sub->parsed()) continue;
    try {
      return run();
    } catch (const hovs::Error& e) {
      std::cerr << "hovs " << sub->get_name() << ": error: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "hovs " << sub->get_name() << ": internal error: " << e.what() << "\n";
      return 3;
    }
  }
  return 1;
}
