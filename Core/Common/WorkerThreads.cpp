// SPDX-License-Identifier: BSD-3-Clause
#include "Common/WorkerThreads.h"

#include <algorithm>
#include <cstdlib>
#include <thread>

#ifdef __linux__
#include <pthread.h>
#endif

namespace faceplan {

namespace {

// Read once: the value must not change between the steps of one precompute.
int EnvironmentLimit() {
  static const int limit = [] {
    const char* text = std::getenv("FACEPLAN_THREADS");
    if (!text)
      return 0;
    char* end = nullptr;
    const long value = std::strtol(text, &end, 10);
    return (end != text && *end == '\0' && value > 0 && value < 4096) ? static_cast<int>(value) : 0;
  }();
  return limit;
}

} // namespace

int WorkerThreads(int cap) {
  int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  threads = std::min(threads, std::max(1, cap));
  if (const int limit = EnvironmentLimit(); limit > 0)
    threads = std::min(threads, limit);
  return threads;
}

void NameThisThread(const char* name) {
#ifdef __linux__
  pthread_setname_np(pthread_self(), name); // fails only on a name over 15 characters
#else
  (void)name;
#endif
}

} // namespace faceplan
