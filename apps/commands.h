// The subcommand table of the hovs executable. Each entry registers its options on a CLI11 subcommand and
// returns the function that runs it. apps/ only parses options and calls the libraries.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace hovs::apps {

struct GlobalOptions {
  bool quiet = false;
  bool json = false;  // print the machine-readable result on stdout
};

using Runner = std::function<int()>;

struct Command {
  const char* name;
  const char* help;
  std::function<Runner(CLI::App* sub, const GlobalOptions* global)> setup;
};

const std::vector<Command>& Commands();

// One entry per subcommand, defined in cmd_<name>.cc.
Runner SetupDesign(CLI::App* sub, const GlobalOptions* global);
Runner SetupVersion(CLI::App* sub, const GlobalOptions* global);
Runner SetupRender(CLI::App* sub, const GlobalOptions* global);
Runner SetupDataset(CLI::App* sub, const GlobalOptions* global);
Runner SetupCalibrate(CLI::App* sub, const GlobalOptions* global);
Runner SetupUnwrap(CLI::App* sub, const GlobalOptions* global);
Runner SetupDepth(CLI::App* sub, const GlobalOptions* global);
Runner SetupStereoCalibrate(CLI::App* sub, const GlobalOptions* global);

}  // namespace hovs::apps
