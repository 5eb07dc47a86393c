// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Splits [0, count) into one contiguous range per hardware thread, the first run on the calling
// thread and the others on its helpers (HelperThreads.h); runs inline when small.
#include "Common/HelperThreads.h"
#include "Common/WorkerThreads.h"
#include <algorithm>
#include <cstdint>

namespace faceplan {

template <class Work> void ParallelFor(std::int64_t count, std::int64_t serialBelow, Work&& work) {
  const std::int64_t threads = WorkerThreads(16);
  if (count < serialBelow || threads == 1) {
    work(std::int64_t{0}, count);
    return;
  }
  const std::int64_t chunk = (count + threads - 1) / threads;
  const int parts = static_cast<int>((count + chunk - 1) / chunk);
  RunOnHelpers(parts, [&work, chunk, count](int part) {
    const std::int64_t begin = part * chunk, end = std::min(count, begin + chunk);
    work(begin, end);
  });
}

} // namespace faceplan
