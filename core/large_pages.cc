#include "core/large_pages.h"

#include <cstdint>
#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hovs {
namespace {
std::size_t RoundUp(std::size_t bytes) { return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes; }
}  // namespace

#if defined(__linux__)
void* AllocateLargePages(std::size_t bytes) {
  const std::size_t len = RoundUp(bytes);
  if (len < bytes || len + kHugePageBytes < len) throw std::bad_alloc();
  // Over-map by one huge page, then unmap the unaligned head and the tail: what stays is [p, p + len),
  // 2 MiB aligned, which FreeLargePages unmaps from the byte count alone.
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

void FreeLargePages(void* p, std::size_t bytes) noexcept {
  if (p != nullptr) munmap(p, RoundUp(bytes));
}
#else
void* AllocateLargePages(std::size_t bytes) {
  void* p = std::aligned_alloc(kHugePageBytes, RoundUp(bytes));
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

void FreeLargePages(void* p, std::size_t) noexcept { std::free(p); }
#endif

bool KeepFreedMemoryForReuse() {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  // 32 MiB is the largest mmap threshold glibc accepts on 64-bit (it bounds the per-thread heaps' blocks).
  return mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1 && mallopt(M_TRIM_THRESHOLD, 1 << 30) == 1;
#else
  return false;
#endif
}

}  // namespace hovs
