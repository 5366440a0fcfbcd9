// Large buffers in transparent huge pages. A frame's buffers (a 2750 x 2200 render with ground truth holds
// 362 MB) are first touched page by page; on a virtual machine each 4 KiB page fault can cost microseconds
// (measured on a paravirtualised Zen 5 VM of this project: 362 MB touched by one thread in 4 KiB pages ~1 s,
// in 2 MiB pages ~25 ms).
// Buffers of at least kLargeBytes are therefore mapped on a 2 MiB boundary and advised MADV_HUGEPAGE
// (honoured when the kernel's transparent_hugepage setting is "madvise" or "always"; otherwise they are
// ordinary pages). Smaller buffers come from operator new.
#pragma once

#include <cstddef>
#include <new>

namespace hovs {

inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;
inline constexpr std::size_t kLargeBytes = std::size_t(4) << 20;

// Memory for `bytes` bytes, 2 MiB aligned; throws std::bad_alloc when it cannot be mapped. FreeLargePages
// takes the same byte count.
void* AllocateLargePages(std::size_t bytes);
void FreeLargePages(void* p, std::size_t bytes) noexcept;

// Frame-sized work (depth matching, image reading and writing, OpenCV's own buffers) allocates and frees tens of
// megabytes per frame through malloc, which by default hands blocks above its (adaptive, at most 32 MiB) mmap
// threshold back to the kernel when they are freed, so every frame faults them in again. Called once at start
// (the hovs command and the benchmark programs do), this makes glibc's malloc serve blocks below 32 MiB from its
// heaps and keep up to 1 GiB of freed memory mapped for reuse: measured on a Zen 5 VM (4 KiB page faults ~11 us),
// BM_DenseDepth/320/1 163-173 -> 79-96 ms. The price is that a process keeps that much freed memory. Returns
// false where the allocator has no such settings (not glibc, or a sanitizer's allocator); nothing changes then.
bool KeepFreedMemoryForReuse();

// A std::allocator whose large allocations use AllocateLargePages; UninitialisedConstruct leaves elements
// default-initialised (no zeroing on resize: the renderer fills its frames in parallel).
template <class T, bool UninitialisedConstruct = false>
struct LargePageAllocator {
  static_assert(alignof(T) <= __STDCPP_DEFAULT_NEW_ALIGNMENT__, "over-aligned types need an aligned operator new");
  using value_type = T;
  template <class U>
  struct rebind {
    using other = LargePageAllocator<U, UninitialisedConstruct>;
  };
  LargePageAllocator() = default;
  template <class U>
  LargePageAllocator(const LargePageAllocator<U, UninitialisedConstruct>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes >= kLargeBytes) return static_cast<T*>(AllocateLargePages(bytes));
    return static_cast<T*>(::operator new(bytes));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    const std::size_t bytes = n * sizeof(T);
    if (bytes >= kLargeBytes)
      FreeLargePages(p, bytes);
    else
      ::operator delete(p);
  }
  template <class U>
  void construct(U* p) noexcept(UninitialisedConstruct) {
    if constexpr (UninitialisedConstruct)
      ::new (static_cast<void*>(p)) U;
    else
      ::new (static_cast<void*>(p)) U();
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(static_cast<Args&&>(args)...);
  }
  template <class U>
  bool operator==(const LargePageAllocator<U, UninitialisedConstruct>&) const noexcept {
    return true;
  }
  template <class U>
  bool operator!=(const LargePageAllocator<U, UninitialisedConstruct>&) const noexcept {
    return false;
  }
};

}  // namespace hovs
