// hovs: one command, subcommands from the table in commands.cc.
#include <glog/logging.h>

#include "apps/commands.h"

int main(int argc, char** argv) {
  // Ceres logs through glog; hovs reports what matters itself.
  FLAGS_minloglevel = 3;
  google::InitGoogleLogging(argv[0]);
  return hovs::apps::RunCommandLine(argc, argv, false);
}
