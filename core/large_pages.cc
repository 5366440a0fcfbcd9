#include "core/large_pages.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <string_view>
#include <cstdlib>
#include <iterator>
#include <mutex>
#include <utility>
#include <vector>

#include "core/error.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hovs {
namespace {
std::size_t RoundUp(std::size_t bytes) { return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes; }

#if defined(__linux__)
// len: a multiple of 2 MiB.
void* MapLarge(std::size_t len) {
  if (len + kHugePageBytes < len) throw std::bad_alloc();
  // Over-map by one huge page, then unmap the unaligned head and the tail: what stays is [p, p + len),
  // 2 MiB aligned, which UnmapLarge unmaps from the length alone.
  void* raw = mmap(nullptr, len + kHugePageBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) throw std::bad_alloc();
  const auto base = reinterpret_cast<std::uintptr_t>(raw);
  const std::uintptr_t aligned = (base + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
  if (aligned > base) munmap(raw, aligned - base);
  const std::size_t tail = base + len + kHugePageBytes - (aligned + len);
  if (tail > 0) munmap(reinterpret_cast<void*>(aligned + len), tail);
  void* p = reinterpret_cast<void*>(aligned);
  madvise(p, len, MADV_HUGEPAGE);  // advice only: without THP the pages are ordinary ones
  return p;
}
void UnmapLarge(void* p, std::size_t len) noexcept { munmap(p, len); }
#else
void* MapLarge(std::size_t len) {
  void* p = std::aligned_alloc(kHugePageBytes, len);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void UnmapLarge(void* p, std::size_t) noexcept { std::free(p); }
#endif

// The freed buffers kept for reuse, longest kept first.
struct KeptBuffers {
  std::mutex mutex;
  std::size_t max_bytes = 0, bytes = 0;
  std::vector<std::pair<void*, std::size_t>> buffers;  // (address, length)

  // Unmaps the longest kept buffers until at most `limit` bytes are kept. Caller holds the mutex.
  void TrimTo(std::size_t limit) noexcept {
    std::size_t k = 0;
    for (; k < buffers.size() && bytes > limit; ++k) {
      UnmapLarge(buffers[k].first, buffers[k].second);
      bytes -= buffers[k].second;
    }
    buffers.erase(buffers.begin(), buffers.begin() + static_cast<std::ptrdiff_t>(k));
  }
};
KeptBuffers& Kept() {
  static KeptBuffers* kept = new KeptBuffers;  // never destroyed: buffers may be freed during static destruction
  return *kept;
}
}  // namespace

void* AllocateLargePages(std::size_t bytes) {
  const std::size_t len = RoundUp(bytes);
  if (len < bytes) throw std::bad_alloc();
  {
    KeptBuffers& kept = Kept();
    const std::lock_guard<std::mutex> lock(kept.mutex);
    for (auto it = kept.buffers.rbegin(); it != kept.buffers.rend(); ++it)
      if (it->second == len) {
        void* p = it->first;
        kept.bytes -= len;
        kept.buffers.erase(std::next(it).base());
        return p;
      }
  }
  return MapLarge(len);
}

void FreeLargePages(void* p, std::size_t bytes) noexcept {
  if (p == nullptr) return;
  const std::size_t len = RoundUp(bytes);
  KeptBuffers& kept = Kept();
  {
    const std::lock_guard<std::mutex> lock(kept.mutex);
    if (len <= kept.max_bytes) {
      kept.TrimTo(kept.max_bytes - len);
      try {
        kept.buffers.emplace_back(p, len);
        kept.bytes += len;
        return;
      } catch (...) {  // no memory for the list's entry: unmap instead
      }
    }
  }
  UnmapLarge(p, len);
}

std::size_t KeepFreedLargePages(std::size_t max_bytes) {
  KeptBuffers& kept = Kept();
  const std::lock_guard<std::mutex> lock(kept.mutex);
  const std::size_t previous = kept.max_bytes;
  kept.max_bytes = max_bytes;
  kept.TrimTo(max_bytes);
  return previous;
}

std::size_t KeptLargePageBytes() {
  KeptBuffers& kept = Kept();
  const std::lock_guard<std::mutex> lock(kept.mutex);
  return kept.bytes;
}

namespace {
// The first number in a file (e.g. "max" gives nullopt), or the value of `key` in a "key: value kB" file.
std::optional<std::size_t> ReadNumber(const char* path, const std::string& key = "") {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::string_view rest(line);
    if (!key.empty()) {
      if (rest.substr(0, key.size() + 1) != key + ":") continue;
      rest.remove_prefix(key.size() + 1);
    }
    while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
    std::size_t value = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), value);
    if (ec != std::errc() || end == rest.data()) return std::nullopt;
    rest.remove_prefix(static_cast<std::size_t>(end - rest.data()));
    while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
    if (rest == "kB") value *= 1024;
    return value;
  }
  return std::nullopt;
}
}  // namespace

std::optional<std::size_t> AvailableMemoryBytes() {
  std::optional<std::size_t> available;
  if (const auto kb = ReadNumber("/proc/meminfo", "MemAvailable")) available = *kb + KeptLargePageBytes();
  // The process's memory cgroup: v2 ("0::<path>" in /proc/self/cgroup; memory.max, "max" when unlimited, and
  // memory.current) or v1 ("<n>:memory:<path>"; memory.limit_in_bytes and memory.usage_in_bytes).
  std::ifstream in("/proc/self/cgroup");
  for (std::string line; std::getline(in, line);) {
    std::string dir, max_file, current_file;
    if (line.rfind("0::", 0) == 0) {
      dir = "/sys/fs/cgroup" + line.substr(3), max_file = "memory.max", current_file = "memory.current";
    } else if (const auto at = line.find(":memory:"); at != std::string::npos) {
      dir = "/sys/fs/cgroup/memory" + line.substr(at + 8), max_file = "memory.limit_in_bytes",
      current_file = "memory.usage_in_bytes";
    } else {
      continue;
    }
    if (!dir.empty() && dir.back() == '/') dir.pop_back();
    const auto max = ReadNumber((dir + "/" + max_file).c_str());
    const auto current = ReadNumber((dir + "/" + current_file).c_str());
    if (!max || !current) continue;
    const std::size_t room = *max > *current ? *max - *current : 0;
    available = available ? std::min(*available, room) : room;
  }
  return available;
}

void RequireMemory(const std::string& where, const std::string& what, std::size_t need,
                   std::optional<std::size_t> available, const std::string& remedy) {
  if (!available || need <= *available) return;
  char text[96];
  std::snprintf(text, sizeof text,
                " needs %.2f GB of memory; %.2f GB are available: ", static_cast<double>(need) * 1e-9,
                static_cast<double>(*available) * 1e-9);
  throw Error(where, what + text + remedy);
}

bool KeepFreedMemoryForReuse() {
  KeepFreedLargePages(kKeptFreedBytes);
#if defined(__GLIBC__) && !defined(HOVS_ADDRESS_SANITIZER)
  // 32 MiB is the largest mmap threshold glibc accepts on 64-bit (it bounds the per-thread heaps' blocks).
  return mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1 && mallopt(M_TRIM_THRESHOLD, 1 << 30) == 1;
#else
  return false;
#endif
}

}  // namespace hovs
