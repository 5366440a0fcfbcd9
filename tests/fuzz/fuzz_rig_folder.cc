// rig.json of a rig folder (rig/rig_study.h LoadRigFolder) against the reference machine: the record and every
// path and checksum it names (the files mostly do not exist: each must be refused by name).
#include <unistd.h>

#include <filesystem>

#include "core/io.h"
#include "rig/rig_study.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  static const hovs::rig::TurretSpec spec = hovs::rig::LoadTurretSpec("scenes/turret.yaml");
  static const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hovs-fuzz-rig-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  hovs::WriteFileAtomic(dir / "rig.json", input);
  hovs::rig::LoadRigFolder(dir / "rig.json", spec);
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
