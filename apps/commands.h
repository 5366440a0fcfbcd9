// The subcommand table of the hovs executable. Each entry registers its options on a CLI11 subcommand and
// returns the function that runs it. apps/ only parses options and calls the libraries.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"

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

// The bounds of a numeric option: its value must be finite and in [lo, hi] (with low_open, in (lo, hi]). CLI11's
// Range lets NaN through, and an unbounded option once reached OpenCV as 1024000 disparities. Every numeric
// option of every command carries one of these (its validator is named "bounded"; a test walks the table).
CLI::Validator Bounded(double lo, double hi, bool low_open = false);

// A numeric option with its bounds (Bounded) and its default shown in the help.
template <class T>
CLI::Option* AddBounded(CLI::App* app, const std::string& name, T* value, const std::string& help, double lo, double hi,
                        bool low_open = false) {
  return app->add_option(name, *value, help)->check(Bounded(lo, hi, low_open))->capture_default_str();
}

// Runs a library stage on an input the user named (a dataset, a folder of images, a camera): an error of the
// stage that does not name that input is given its name, so that the one error line says which input failed
// ("<input> (<stage>): <problem>").
template <class F>
auto OnInput(const std::string& input, F&& stage) -> decltype(stage()) {
  try {
    return stage();
  } catch (const Error& e) {
    if (input.empty() || e.where().find(input) != std::string::npos) throw;
    throw Error(input + (e.where().empty() ? "" : " (" + e.where() + ")"), e.message());
  }
}

// Every library version a hovs output may depend on, recorded in each output's "versions": hovs itself, the
// compiler, Eigen, Ceres, VTK, NLopt, TBB (design), Embree, OpenImageIO, OpenEXR (raytrace), OpenCV (calib) and
// Aravis (hw).
std::map<std::string, std::string> Versions();

// An image size "WxH" given to `option` (1..65535 pixels a side), or an error naming the option.
void ParseImageSize(const std::string& text, const std::string& option, int* width, int* height);

// Parses and runs one command line (argv[0] is the program). rethrow = false: errors are printed and turned into
// exit codes (2 bad input, 3 internal); rethrow = true: hovs::Error propagates (used by hovs validate, which
// names the failing stage).
int RunCommandLine(int argc, const char* const* argv, bool rethrow);
int RunCommandLine(const std::vector<std::string>& args, bool rethrow);  // args without the program name

// --shard "I/N" into *index, *count; without it, Slurm's SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT where
// Slurm sets them; else both stay as they are (the whole set). Throws naming the option or the variables.
void ParseShard(const std::string& text, int* index, int* count);

// One entry per subcommand, defined in cmd_<name>.cc.
Runner SetupDesign(CLI::App* sub, const GlobalOptions* global);
Runner SetupVersion(CLI::App* sub, const GlobalOptions* global);
Runner SetupRender(CLI::App* sub, const GlobalOptions* global);
Runner SetupDataset(CLI::App* sub, const GlobalOptions* global);
Runner SetupCalibrate(CLI::App* sub, const GlobalOptions* global);
Runner SetupUnwrap(CLI::App* sub, const GlobalOptions* global);
Runner SetupDepth(CLI::App* sub, const GlobalOptions* global);
Runner SetupStereoCalibrate(CLI::App* sub, const GlobalOptions* global);
Runner SetupValidate(CLI::App* sub, const GlobalOptions* global);
Runner SetupCapture(CLI::App* sub, const GlobalOptions* global);
Runner SetupLive(CLI::App* sub, const GlobalOptions* global);
Runner SetupSlurm(CLI::App* sub, const GlobalOptions* global);
Runner SetupPosition(CLI::App* sub, const GlobalOptions* global);
Runner SetupCompare(CLI::App* sub, const GlobalOptions* global);
Runner SetupConvert(CLI::App* sub, const GlobalOptions* global);
Runner SetupMerge(CLI::App* sub, const GlobalOptions* global);
Runner SetupExport(CLI::App* sub, const GlobalOptions* global);
Runner SetupRig(CLI::App* sub, const GlobalOptions* global);
Runner SetupTolerance(CLI::App* sub, const GlobalOptions* global);
Runner SetupEdgeCheck(CLI::App* sub, const GlobalOptions* global);

}  // namespace hovs::apps
