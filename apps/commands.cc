#include "apps/commands.h"

#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "calib/checkerboard_detector.h"
#include "core/error.h"
#include "core/io.h"
#include "core/shard_set.h"
#include "core/version.h"
#include "design/study.h"
#include "hw/camera_source.h"
#include "raytrace/render.h"

namespace hovs::apps {
namespace {

// Errors print on one line: a multi-line message (a list of images) is joined with "; ".
std::string OneLine(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\n') {
      out += s[i];
      continue;
    }
    while (!out.empty() && (out.back() == ':' || out.back() == ' ')) out.pop_back();
    out += "; ";
    while (i + 1 < s.size() && s[i + 1] == ' ') ++i;
  }
  return out;
}

std::string FileSystemMessage(const std::filesystem::filesystem_error& e) {
  std::string what = e.code().message();
  if (!e.path1().empty()) return e.path1().string() + ": " + what;
  return what;
}

// A given --out is checked before the command does any work (CheckOutputFolder): every other option whose value
// names an existing file or folder is one of its inputs. The command checks again when it writes.
void CheckOutputOption(const CLI::App& sub, const std::string& parent = "") {
  const std::string name = parent.empty() ? sub.get_name() : parent + " " + sub.get_name();
  for (const CLI::App* nested : sub.get_subcommands()) CheckOutputOption(*nested, name);  // hovs rig align ...
  const CLI::Option* out = sub.get_option_no_throw("--out");
  if (out == nullptr || out->count() == 0) return;
  const std::string target = out->results().front();
  if (target.empty()) return;
  std::vector<std::filesystem::path> inputs;
  for (const CLI::Option* opt : sub.get_options()) {
    if (opt == out || opt->get_name() == "--save-map" || opt->get_name() == "--layout-out") continue;
    for (const std::string& value : opt->results()) {
      std::error_code ec;
      if (!value.empty() && std::filesystem::exists(value, ec)) inputs.emplace_back(value);
    }
  }
  CheckOutputFolder(target, name, inputs);
}

}  // namespace

std::map<std::string, std::string> Versions() {
  auto v = design::DesignVersions();
  for (const auto& more : {raytrace::RaytraceVersions(), calib::CalibVersions(), hw::HwVersions()})
    v.insert(more.begin(), more.end());
  return v;
}

CLI::Validator Bounded(double lo, double hi, bool low_open) {
  const std::string range =
      std::string(low_open ? "(" : "[") + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]";
  CLI::Validator v(
      [lo, hi, low_open, range](std::string& text) -> std::string {
        char* end = nullptr;
        errno = 0;
        const double x = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(x))
          return "'" + text + "' is not a finite number";
        if (x > hi || x < lo || (low_open && x == lo)) return "'" + text + "' is outside " + range;
        return std::string();
      },
      "in " + range, "bounded");
  return v;
}

void ParseShard(const std::string& text, int* index, int* count) {
  std::string spec = text, where = "--shard";
  const char* id = std::getenv("SLURM_ARRAY_TASK_ID");
  const char* n = std::getenv("SLURM_ARRAY_TASK_COUNT");
  if (spec.empty() && id && n) spec = std::string(id) + "/" + n, where = "SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT";
  if (spec.empty()) return;
  ParseShardSpec(spec, where, index, count);
}

const std::vector<Command>& Commands() {
  static const std::vector<Command> table = {
      {"design", "Mirror design study: sweep (a, b[, d]), constrained optima, report with figures", SetupDesign},
      {"render", "Render a scene through its catadioptric units, with ground truth (EXR + JSON)", SetupRender},
      {"dataset", "Render a dataset (a monocular calibration set) with ground truth and a manifest", SetupDataset},
      {"calibrate", "Monocular calibration (polynomial and unified models) from a corner table or a dataset",
       SetupCalibrate},
      {"unwrap", "Virtual perspective views and panoramas from catadioptric images (any model), mapping files",
       SetupUnwrap},
      {"stereo-calibrate",
       "Relative pose of two units from ArUco board pairs (detection in unwrapped views, joint solve)",
       SetupStereoCalibrate},
      {"depth", "Dense and sparse binocular depth of a two-unit dataset (rectification, SGBM, point clouds)",
       SetupDepth},
      {"capture",
       "Capture frames from GigE Vision cameras (Aravis), a replay or the GigE Vision simulator into a dataset",
       SetupCapture},
      {"compare", "The difference between two models of one camera as a map over the image (px and degrees)",
       SetupCompare},
      {"merge", "Join the shards of a dataset or a tolerance study (--shard I/N) into what one process writes",
       SetupMerge},
      {"tolerance",
       "Tolerance study of a design: Monte-Carlo over manufacturing and assembly errors, sensitivities, the "
       "tolerances a limit needs",
       SetupTolerance},
      {"edge-check",
       "The blur prediction against the renderer: slanted edges rendered through the thin lens, their MTF50 "
       "against the exact spot's",
       SetupEdgeCheck},
      {"slurm", "A sharded command as a Slurm array job: submit (and wait, merge), status", SetupSlurm},
      {"convert",
       "A camera model into other tools' files: Kalibr camchain, MEI YAML, OpenCV omnidir YAML; refits to double "
       "sphere, EUCM, Kannala-Brandt with their error",
       SetupConvert},
      {"export", "A rendered dataset for learning pipelines: equirectangular RGB, range and mask, and the poses",
       SetupExport},
      {"rig",
       "The variable-scale unit in simulation: align a mirror from disturbed starts, switch mirrors (turret, rod, "
       "alignment, focus)",
       SetupRig},
      {"position", "Visual positioning: the camera's offset from the mirror design, from the rim in one image",
       SetupPosition},
      {"live",
       "Live expansion: camera (or simulator, replay) frames into views, raw Bayer to RGB, with latency figures",
       SetupLive},
      {"validate",
       "End to end against ground truth: design, renders, detection, calibration, stereo, views, depth; report",
       SetupValidate},
      {"version", "Print the versions of hovs and its libraries", SetupVersion},
  };
  return table;
}

void ParseImageSize(const std::string& text, const std::string& option, int* w, int* h) {
  char x = 0;
  int end = -1;
  HOVS_REQUIRE(std::sscanf(text.c_str(), "%d%c%d%n", w, &x, h, &end) == 3 && x == 'x' &&
                   end == static_cast<int>(text.size()) && *w > 0 && *h > 0 && *w <= 65535 && *h <= 65535,
               option, "expected WxH of 1..65535 pixels each, e.g. 1024x768 (got '", text, "')");
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
  // An unknown subcommand or global option before it is named as such (CLI11 would say that a subcommand is
  // required).
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    std::string message;
    if (arg.empty() || arg[0] != '-') {
      bool known = false;
      for (const auto& cmd : Commands()) known = known || arg == cmd.name;
      if (!known) message = "unknown command '" + arg + "' (hovs --help lists them)";
    } else if (arg != "-q" && arg != "--quiet" && arg != "--json" && arg != "-h" && arg != "--help" &&
               arg != "--version") {
      message = "unknown option '" + arg + "' before the command (hovs --help lists the options)";
    } else {
      continue;
    }
    if (message.empty()) break;  // the command: its own options follow
    if (rethrow) throw Error("command line", message);
    std::cerr << "hovs: error: " << message << "\n";
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (rethrow) throw Error("command line", std::string(e.what()));
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version: CLI11's own output
    // Any other command-line error is bad input like the rest: one line, exit 2.
    std::cerr << "hovs: error: " << e.what() << " (see --help)\n";
    return 2;
  }
  for (auto& [sub, run] : runners) {
    if (!sub->parsed()) continue;
    ClearNotedInputs();
    if (rethrow) {
      CheckOutputOption(*sub);
      return run();
    }
    try {
      CheckOutputOption(*sub);
      return run();
    } catch (const Error& e) {
      // An error raised by the command itself names it already ("hovs merge: ..."): said once.
      const std::string prefix = "hovs " + sub->get_name() + ": ";
      std::string message = OneLine(e.what());
      if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
      std::cerr << prefix << "error: " << message << "\n";
      return 2;
    } catch (const std::filesystem::filesystem_error& e) {
      // A file system refusal (permissions, a full disk, a path that is a file) is about the paths given.
      std::cerr << "hovs " << sub->get_name() << ": error: " << FileSystemMessage(e) << "\n";
      return 2;
    } catch (const std::bad_alloc&) {
      std::cerr << "hovs " << sub->get_name() << ": error: out of memory (an input or option asks for more memory "
                << "than this machine has)\n";
      return 3;
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
