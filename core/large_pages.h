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
#include <optional>
#include <string>

// Defined when AddressSanitizer instruments this build (GCC names it __SANITIZE_ADDRESS__, clang a feature).
#if defined(__SANITIZE_ADDRESS__)
#define HOVS_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HOVS_ADDRESS_SANITIZER 1
#endif
#endif

namespace hovs {

inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;
inline constexpr std::size_t kLargeBytes = std::size_t(4) << 20;

// Memory for `bytes` bytes, 2 MiB aligned; throws std::bad_alloc when it cannot be mapped. FreeLargePages
// takes the same byte count. The memory's content is unspecified: a buffer kept for reuse (below) holds what its
// previous owner wrote.
void* AllocateLargePages(std::size_t bytes);
void FreeLargePages(void* p, std::size_t bytes) noexcept;

// Freed large buffers kept mapped for reuse, up to max_bytes in all (0, the default: they are unmapped when
// freed). AllocateLargePages then hands out a kept buffer of the same size (in 2 MiB pages) before it maps new
// memory; when a freed buffer does not fit, the longest-kept ones are unmapped to make room. The point is the
// renderer's frames (Render allocates 362 MB per 2750 x 2200 frame with ground truth): memory mapped anew is
// faulted in page by page, and on a virtual machine whose guest reports free memory to its hypervisor (free page
// reporting, as on the Firecracker VMs this project is measured on) memory left unmapped for more than about
// 1.5 s comes back through host page faults, 130-240 ms per frame there (tests/bench/render_bench.cc,
// BM_FrameMemoryFirstTouch), against none for a kept buffer. Calling with 0 unmaps what is kept. Returns the
// previous limit.
std::size_t KeepFreedLargePages(std::size_t max_bytes);
// The bytes of freed large buffers kept mapped now.
std::size_t KeptLargePageBytes();

// Frame-sized work (depth matching, image reading and writing, OpenCV's own buffers) allocates and frees tens of
// megabytes per frame through malloc, which by default hands blocks above its (adaptive, at most 32 MiB) mmap
// threshold back to the kernel when they are freed, so every frame faults them in again. Called once at start
// (the hovs command and the benchmark programs do), this makes glibc's malloc serve blocks below 32 MiB from its
// heaps and keep up to 1 GiB of freed memory mapped for reuse: measured on a Zen 5 VM (4 KiB page faults ~11 us),
// BM_DenseDepth/320/1 163-173 -> 79-96 ms. It also keeps up to 1 GiB of freed large buffers
// (KeepFreedLargePages). The price is that a process keeps that much freed memory. Returns false where malloc
// has no such settings (not glibc, or a sanitizer's allocator); malloc's settings do not change then, the large
// buffers are kept all the same.
bool KeepFreedMemoryForReuse();
inline constexpr std::size_t kKeptFreedBytes = std::size_t(1) << 30;

// The memory this process can still take without the kernel's out-of-memory killer ending it, in bytes: the
// kernel's MemAvailable (/proc/meminfo) plus the freed large buffers kept for reuse, and no more than the room left
// under the process's cgroup limit (cgroup v2 memory.max less memory.current) where there is one; nullopt where
// neither is known (not Linux). Linux overcommits, so an allocation larger than this succeeds and the process is
// killed when it touches the memory: callers that allocate by the user's request (the renderer's frames) check
// first and report the request instead.
std::optional<std::size_t> AvailableMemoryBytes();
// Throws Error(where, "<what> needs <need> GB of memory; <available> GB are available: <remedy>") when need exceeds
// available (nullopt: unknown, no check): the check of a request whose size the user chose, before any of it is
// taken.
void RequireMemory(const std::string& where, const std::string& what, std::size_t need,
                   std::optional<std::size_t> available, const std::string& remedy);

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
