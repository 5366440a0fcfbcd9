// hovs: one command, subcommands from the table in commands.cc.
#include <glog/logging.h>

#include "apps/commands.h"
#include "core/interrupt.h"
#include "core/large_pages.h"

int main(int argc, char** argv) {
  // First, before any thread starts: an interrupt removes the staging folders of the run (core/interrupt.h).
  hovs::InstallInterruptHandling();
  // Ceres logs through glog; hovs reports what matters itself.
  FLAGS_minloglevel = 3;
  google::InitGoogleLogging(argv[0]);
  // Frame-sized buffers freed by one frame are reused by the next instead of being faulted in again.
  hovs::KeepFreedMemoryForReuse();
  return hovs::apps::RunCommandLine(argc, argv, false);
}
