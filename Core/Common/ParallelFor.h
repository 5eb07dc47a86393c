// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Splits [0, count) into one contiguous range per hardware thread; runs inline when small.
#include "Common/WorkerThreads.h"
#include <algorithm>
#include <cstdint>
#include <thread>
#include <vector>

namespace faceplan {

template <class Work> void ParallelFor(std::int64_t count, std::int64_t serialBelow, Work&& work) {
  const std::int64_t threads = WorkerThreads(16);
  if (count < serialBelow || threads == 1) {
    work(std::int64_t{0}, count);
    return;
  }
  std::vector<std::thread> pool;
  const std::int64_t chunk = (count + threads - 1) / threads;
  for (std::int64_t t = 0; t < threads; ++t) {
    const std::int64_t begin = t * chunk, end = std::min(count, begin + chunk);
    if (begin < end)
      pool.emplace_back([&work, begin, end] { work(begin, end); });
  }
  for (auto& th : pool)
    th.join();
}

} // namespace faceplan
