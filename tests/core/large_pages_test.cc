#include "core/large_pages.h"

#include <gtest/gtest.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace hovs {
namespace {

using LargeFloats = std::vector<float, LargePageAllocator<float>>;

TEST(LargePages, LargeBuffersAreHugePageAlignedAndWholeRangeWritable) {
  for (const std::size_t bytes : {kLargeBytes, kLargeBytes + 1, std::size_t(362) << 20}) {
    auto* p = static_cast<unsigned char*>(AllocateLargePages(bytes));
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % kHugePageBytes, 0u) << bytes;
    p[0] = 1, p[bytes / 2] = 2, p[bytes - 1] = 3;
    EXPECT_EQ(p[0] + p[bytes / 2] + p[bytes - 1], 6) << bytes;
    FreeLargePages(p, bytes);
  }
}

TEST(LargePages, VectorKeepsItsContentAcrossTheLargeThreshold) {
  LargeFloats v;
  const std::size_t large = kLargeBytes / sizeof(float) * 3;
  for (std::size_t i = 0; i < large; ++i) v.push_back(static_cast<float>(i % 1000));  // small -> large buffers
  bool same = true;
  for (std::size_t i = 0; i < large; ++i) same = same && v[i] == static_cast<float>(i % 1000);
  EXPECT_TRUE(same);
  v.resize(100);
  v.shrink_to_fit();  // large -> small buffer
  for (std::size_t i = 0; i < 100; ++i) ASSERT_EQ(v[i], static_cast<float>(i)) << i;
  v.assign(large, 0.0f);
  v.resize(large / 2);
  v.resize(large, 0.0f);  // value-initialising allocator: zeros again
  float sum = 0;
  for (const float x : v) sum += x;
  EXPECT_EQ(sum, 0.0f);
}

// The advice reaches the kernel: the mapping is eligible for transparent huge pages exactly when the kernel's
// setting allows them (not "[never]").
TEST(LargePages, MappingIsAdvisedForTransparentHugePages) {
  std::ifstream setting("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  std::getline(setting, mode);
  const std::size_t bytes = std::size_t(8) << 20;
  auto* p = static_cast<char*>(AllocateLargePages(bytes));
  p[0] = 1;
  std::ifstream smaps("/proc/self/smaps");
  ASSERT_TRUE(smaps.good());
  const auto addr = reinterpret_cast<std::uintptr_t>(p);
  std::string line;
  bool in_mapping = false;
  int eligible = -1;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      in_mapping = lo <= addr && addr < hi;
      if (in_mapping) { EXPECT_GE(hi - addr, bytes); }
    } else if (in_mapping && line.rfind("THPeligible:", 0) == 0) {
      eligible = std::stoi(line.substr(12));
    }
  }
  FreeLargePages(p, bytes);
  ASSERT_FALSE(mode.empty()) << "no transparent_hugepage setting";
  EXPECT_EQ(eligible, mode.find("[never]") == std::string::npos ? 1 : 0) << mode;
}

// Freed large buffers are kept up to the limit and handed out again for the same size (in 2 MiB pages), most
// recently freed first, content included; a buffer that does not fit pushes out the longest kept; 0 unmaps all.
TEST(LargePages, FreedBuffersAreKeptUpToTheLimitAndReusedBySize) {
  const std::size_t mib = std::size_t(1) << 20, previous_limit = KeepFreedLargePages(0);
  EXPECT_EQ(KeptLargePageBytes(), 0u);
  KeepFreedLargePages(16 * mib);
  auto* a = static_cast<unsigned char*>(AllocateLargePages(8 * mib));
  auto* b = static_cast<unsigned char*>(AllocateLargePages(8 * mib - 100));  // 8 MiB in 2 MiB pages too
  auto* c = static_cast<unsigned char*>(AllocateLargePages(8 * mib));
  a[5] = 1, b[5] = 2, c[5] = 3;
  FreeLargePages(a, 8 * mib);
  FreeLargePages(b, 8 * mib - 100);
  EXPECT_EQ(KeptLargePageBytes(), 16 * mib);
  FreeLargePages(c, 8 * mib);  // does not fit: a, the longest kept, is unmapped
  EXPECT_EQ(KeptLargePageBytes(), 16 * mib);
  auto* d = static_cast<unsigned char*>(AllocateLargePages(10 * mib));  // no kept buffer of that size
  EXPECT_NE(d, b);
  EXPECT_NE(d, c);
  EXPECT_EQ(KeptLargePageBytes(), 16 * mib);
  auto* e = static_cast<unsigned char*>(AllocateLargePages(8 * mib));
  auto* f = static_cast<unsigned char*>(AllocateLargePages(8 * mib - 1));
  EXPECT_EQ(e, c);
  EXPECT_EQ(f, b);
  EXPECT_EQ(e[5] + f[5], 5);  // what their previous owners wrote
  EXPECT_EQ(KeptLargePageBytes(), 0u);
  FreeLargePages(d, 10 * mib);  // 10 MiB: fits alone
  FreeLargePages(e, 8 * mib);   // with d it would not: d is unmapped
  EXPECT_EQ(KeptLargePageBytes(), 8 * mib);
  KeepFreedLargePages(4 * mib);  // a lower limit unmaps what no longer fits
  EXPECT_EQ(KeptLargePageBytes(), 0u);
  FreeLargePages(f, 8 * mib);  // larger than the limit: unmapped at once
  EXPECT_EQ(KeptLargePageBytes(), 0u);
  EXPECT_EQ(KeepFreedLargePages(previous_limit), 4 * mib);
}

// After the call a 16 MiB block comes from malloc's heap (glibc would otherwise map it on its own: the default
// threshold starts at 128 kB) and freeing it keeps it mapped; where the call reports no effect (a sanitizer's
// allocator), that is what it must report.
TEST(LargePages, FreedFrameSizedBlocksStayForReuse) {
  const std::size_t previous_limit = KeepFreedLargePages(0);
  const bool malloc_settings = KeepFreedMemoryForReuse();
  EXPECT_EQ(KeepFreedLargePages(previous_limit), kKeptFreedBytes) << "large buffers are kept in every build";
#if defined(__GLIBC__) && !defined(HOVS_ADDRESS_SANITIZER)
  ASSERT_TRUE(malloc_settings);
  const std::size_t block = std::size_t(16) << 20;
  const auto mapped_blocks = mallinfo2().hblks;
  void* p = std::malloc(block);
  ASSERT_NE(p, nullptr);
  static_cast<volatile char*>(p)[block - 1] = 1;
  EXPECT_EQ(mallinfo2().hblks, mapped_blocks) << "the block was mapped on its own";
  std::free(p);
  const auto heap = mallinfo2();
  EXPECT_GE(heap.fordblks, block) << "the freed block was returned to the kernel";
  void* q = std::malloc(block);
  EXPECT_EQ(mallinfo2().hblks, mapped_blocks);
  std::free(q);
#else
  EXPECT_FALSE(malloc_settings);
#endif
}

}  // namespace
}  // namespace hovs
