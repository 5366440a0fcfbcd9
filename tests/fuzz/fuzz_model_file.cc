// A model file given with --model as JSON: hovs' calibration.json (polynomial and physical models) or a
// dataset manifest's unit, through the commands' own loader (apps/model_files.h). The loader reads files: the
// input is written to a file in memory-backed /dev/shm (or the temporary folder) first.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "apps/model_files.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

const std::filesystem::path& File() {
  static const std::filesystem::path p =
      (std::filesystem::exists("/dev/shm") ? std::filesystem::path("/dev/shm")
                                           : std::filesystem::temp_directory_path()) /
      ("hovs-fuzz-model-" + std::to_string(::getpid()) + ".json");
  return p;
}

void Run(const std::string& input) {
  std::ofstream(File(), std::ios::binary | std::ios::trunc).write(input.data(), std::streamsize(input.size()));
  for (const char* kind : {"auto", "polynomial"}) {
    try {
      hovs::fuzz::UseModel(hovs::apps::LoadCalibratedModel(File(), kind), 8);
    } catch (const hovs::Error&) {}
  }
  hovs::apps::LoadModelSpec(File().string(), "", 10.0);
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
