#include "core/interrupt.h"

#include <pthread.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

namespace hovs {
namespace {
namespace fs = std::filesystem;

std::mutex g_mutex;
std::vector<fs::path>& Registered() {
  static std::vector<fs::path> paths;
  return paths;
}
std::atomic<std::atomic<bool>*> g_flag{nullptr};

sigset_t InterruptSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  return set;
}

void RemoveRegistered() {
  std::lock_guard<std::mutex> lock(g_mutex);
  // Twice: a writer thread may recreate a folder between the first removal and the process's end.
  for (int pass = 0; pass < 2; ++pass)
    for (const auto& p : Registered()) {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
}

[[noreturn]] void EndBySignal(int sig) {
  struct sigaction dfl = {};
  dfl.sa_handler = SIG_DFL;
  sigaction(sig, &dfl, nullptr);
  sigset_t one;
  sigemptyset(&one);
  sigaddset(&one, sig);
  pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
  raise(sig);
  std::_Exit(128 + sig);  // a signal whose default action does not end the process
}

void TakeSignals() {
  const sigset_t set = InterruptSignals();
  // When the first signal asked a command to stop, signals within the next second are the same interrupt
  // (coreutils' timeout sends its signal to the process and again to its group; a double Ctrl-C); a later one
  // ends the process.
  std::chrono::steady_clock::time_point asked{};
  for (;;) {
    int sig = 0;
    if (sigwait(&set, &sig) != 0) continue;
    std::atomic<bool>* flag = g_flag.exchange(nullptr);
    if (flag) {  // the command ends by itself
      flag->store(true);
      asked = std::chrono::steady_clock::now();
      continue;
    }
    if (asked.time_since_epoch().count() != 0 && std::chrono::steady_clock::now() - asked < std::chrono::seconds(1))
      continue;
    RemoveRegistered();
    EndBySignal(sig);
  }
}

}  // namespace

void InstallInterruptHandling() {
  static std::once_flag once;
  std::call_once(once, [] {
    const sigset_t set = InterruptSignals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread(TakeSignals).detach();
  });
}

void RegisterForCleanup(const fs::path& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  Registered().push_back(path);
}

void UnregisterCleanup(const fs::path& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  auto& r = Registered();
  const auto it = std::find(r.begin(), r.end(), path);
  if (it != r.end()) r.erase(it);
}

InterruptScope::InterruptScope(std::atomic<bool>* flag) : previous_(g_flag.exchange(flag)) {}
InterruptScope::~InterruptScope() { g_flag.store(previous_); }

}  // namespace hovs
