// What happens when a hovs process is interrupted (SIGINT, SIGTERM, SIGHUP): the staging folders and temporary
// files it is writing are removed, then the process ends by the signal as it would have without hovs' handling.
// A command that can end cleanly by itself (a capture, a live run) asks instead for the first signal to set a
// flag (InterruptScope); a signal more than a second later removes and ends as above (one within the second is
// taken for the same interrupt: coreutils' timeout sends its signal twice).
//
// The signals are blocked in every thread and taken by one thread of their own (sigwait), so the removal runs as
// ordinary code, not in a signal handler, while the other threads may still be writing: what they create after
// the removal is removed by the next run for the same output (io.h, RemoveStaleStaging).
#pragma once

#include <atomic>
#include <filesystem>

namespace hovs {

// Blocks SIGINT, SIGTERM and SIGHUP and starts the thread that takes them. Call first thing in main(), before
// any other thread exists (threads inherit the blocked set). Idempotent. Without it (tests, library users) the
// signals keep their default action and nothing is removed.
void InstallInterruptHandling();

// Paths removed (recursively) when the process is interrupted. Registered by StagedDirectory and by the atomic
// writers while their temporary exists; unregistered when committed or removed.
void RegisterForCleanup(const std::filesystem::path& path);
void UnregisterCleanup(const std::filesystem::path& path);

// While alive, the first interrupt sets *flag (and nothing is removed); the command checks the flag, ends and
// commits what it has. Scopes do not nest: the innermost one wins.
class InterruptScope {
 public:
  explicit InterruptScope(std::atomic<bool>* flag);
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  std::atomic<bool>* previous_;
};

}  // namespace hovs
