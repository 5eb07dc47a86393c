// SPDX-License-Identifier: BSD-3-Clause
// ReturnLargeAllocationsToSystem: a freed 16 MiB block goes back to the system even after an
// earlier block of that size was freed (glibc's own rule would keep the second one in the heap).
// CTest runs this executable twice: plain, and with MALLOC_MMAP_THRESHOLD_ set by the user
// (FACEPLAN_EXPECT_USER_THRESHOLD=1 tells it which), where the user's setting must be left alone.
#include "Common/LargeAllocations.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

using namespace faceplan;

// GCC names the sanitizers with macros, clang with __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define FACEPLAN_SANITIZED_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) ||                         \
    __has_feature(memory_sanitizer)
#define FACEPLAN_SANITIZED_ALLOCATOR 1
#endif
#endif

namespace {

double ResidentMiB() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0)
      return std::stod(line.substr(6)) / 1024.0;
  return -1.0;
}

// Allocates, touches and frees a block; volatile keeps the compiler from removing the pair.
void UseAndFree(std::size_t bytes) {
  char* volatile block = static_cast<char*>(std::malloc(bytes));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, bytes);
  std::free(block);
}

} // namespace

TEST(LargeAllocations, FreedBlocksLeaveTheProcess) {
#if defined(FACEPLAN_SANITIZED_ALLOCATOR)
  GTEST_SKIP() << "the sanitizers' allocators ignore mallopt";
#elif !defined(__GLIBC__)
  GTEST_SKIP() << "not glibc: nothing to set";
#else
  const bool userThreshold = std::getenv("FACEPLAN_EXPECT_USER_THRESHOLD") != nullptr;
  EXPECT_EQ(ReturnLargeAllocationsToSystem(), !userThreshold);
  EXPECT_EQ(ReturnLargeAllocationsToSystem(), !userThreshold); // once per process
  if (userThreshold)
    return;
  constexpr std::size_t block = std::size_t(16) << 20;
  UseAndFree(block); // with glibc's own rule this raises the threshold past 16 MiB
  const double before = ResidentMiB();
  UseAndFree(block);
  const double after = ResidentMiB();
  EXPECT_LT(after - before, 4.0) << "a freed 16 MiB block stayed resident (" << before << " -> "
                                 << after << " MiB)";
#endif
}
