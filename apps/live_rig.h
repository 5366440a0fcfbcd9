// hovs live on the simulated variable-scale unit (--rig with --simulate MACHINE.yaml).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "apps/commands.h"

namespace hovs::apps {

struct RigLiveCliOptions {
  std::string rig_json, start;
  std::vector<std::string> switches;
  double fps = 10;
  int64_t seed = -1;  // -1: the rig folder's
};

// What the rig run shares with hovs live's other options.
struct RigLiveCommon {
  std::string machine, out, interp;
  int frames = 0, write_every = 0;
  std::map<std::string, std::string> versions;
};

void AddRigLiveOptions(CLI::App* sub, RigLiveCliOptions* o);
int RunRigLiveCommand(const RigLiveCliOptions& c, const RigLiveCommon& common, const GlobalOptions& global);

}  // namespace hovs::apps
