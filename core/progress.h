// A progress line for long commands: items done of the total, the rate in items per minute and the time left at
// that rate, on stderr, one line per step (logs of cluster jobs keep every line) but at most one every two
// seconds, besides the first and the last step (a command over thousands of quick items stays readable).
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace hovs {

class ProgressLine {
 public:
  ProgressLine(std::string what, size_t total, bool enabled)
      : what_(std::move(what)), total_(total), enabled_(enabled), start_(std::chrono::steady_clock::now()) {}
  // Call as item `next` (1-based, of the total) starts: `done` items were finished by this run (items kept from an
  // earlier run are not counted in the rate) and `left` remain, this one included.
  void Step(size_t next, size_t done, size_t left) const {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (printed_ && left > 1 && std::chrono::duration<double>(now - last_).count() < 2.0) return;
    printed_ = true, last_ = now;
    const double s = std::chrono::duration<double>(now - start_).count();
    if (done == 0 || s <= 0) {
      std::fprintf(stderr, "%s %zu/%zu\n", what_.c_str(), next, total_);
      return;
    }
    const double per_min = 60.0 * static_cast<double>(done) / s;
    const double seconds_left = static_cast<double>(left) / per_min * 60.0;
    std::fprintf(stderr, "%s %zu/%zu (%.1f per minute, about %d:%02d left)\n", what_.c_str(), next, total_, per_min,
                 static_cast<int>(seconds_left) / 60, static_cast<int>(seconds_left) % 60);
  }

 private:
  std::string what_;
  size_t total_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
  mutable bool printed_ = false;
  mutable std::chrono::steady_clock::time_point last_;
};

}  // namespace hovs
