// SPDX-License-Identifier: BSD-3-Clause
#include "Common/LargeAllocations.h"

#include <cstdlib>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace faceplan {

bool ReturnLargeAllocationsToSystem() {
#if defined(__GLIBC__)
  static const bool applied = [] {
    const char* user = std::getenv("MALLOC_MMAP_THRESHOLD_");
    if (user && *user)
      return false; // the user's tuning wins
    constexpr int threshold = 4 << 20;
    return mallopt(M_MMAP_THRESHOLD, threshold) == 1;
  }();
  return applied;
#else
  return false;
#endif
}

} // namespace faceplan
