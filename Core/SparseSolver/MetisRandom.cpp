// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/MetisRandom.h"

#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/FillReducingOrdering.h"

#include <cholmod.h>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <vector>

namespace {

// glibc's rand() is random() on a 128-byte (TYPE_3) state; random_r on a state of the same size,
// seeded the same way, gives the same sequence.
struct ThreadRandom {
  random_data data{};
  char state[128] = {};
  bool initialised = false;
  unsigned long long seeds = 0; // how often METIS seeded it (MetisRandomIsPerThread's check)

  void seed(unsigned int value) {
    ++seeds;
    if (!initialised) {
      initstate_r(value, state, sizeof state, &data);
      initialised = true;
    } else {
      srandom_r(value, &data);
    }
  }
  uint32_t next() {
    if (!initialised)
      seed(1); // rand() without srand() starts as after srand(1)
    int32_t value = 0;
    random_r(&data, &value);
    return static_cast<uint32_t>(value);
  }
};

thread_local ThreadRandom threadRandom;

} // namespace

// GKlib's random-number entry points (gk_macros / random.c), as libmetis.so.5 exports and calls
// them. Default visibility so that they are in the dynamic symbol table wherever Core is linked.
extern "C" {

__attribute__((visibility("default"))) void gk_randinit(uint64_t seed) {
  threadRandom.seed(static_cast<unsigned int>(seed)); // srand() takes the low 32 bits
}

__attribute__((visibility("default"))) uint32_t gk_randint32(void) {
  return threadRandom.next();
}

__attribute__((visibility("default"))) uint64_t gk_randint64(void) {
  const uint64_t high = threadRandom.next();
  const uint64_t low = threadRandom.next();
  return (high << 32) | low;
}

} // extern "C"

namespace faceplan {

bool MetisRandomIsPerThread() {
  static const bool perThread = [] {
    // METIS seeds its generator at the start of every call: order a small graph (a cycle of 8
    // nodes) through CHOLMOD and see whether this thread's generator was seeded. (Not dlopen of
    // libmetis: ThreadSanitizer re-reads the loaded libraries on every dlopen and then reports
    // its own suppressions as ambiguous.) Under MetisMutex, in case the answer is no.
    std::lock_guard<std::mutex> metis(MetisMutex());
    constexpr int n = 8;
    std::vector<int> columnStart(n + 1), rows, order(n), dummyRow(1, 0);
    for (int c = 0; c < n; ++c) { // upper pattern: c-1 above c, and 0 above n-1
      columnStart[c] = static_cast<int>(rows.size());
      if (c > 0)
        rows.push_back(c - 1);
      if (c == n - 1)
        rows.push_back(0);
    }
    columnStart[n] = static_cast<int>(rows.size());
    cholmod_sparse graph = ViewPattern(n, columnStart, rows, dummyRow);
    QuietCholmodCommon quiet;
    const unsigned long long before = threadRandom.seeds;
    const bool ordered = cholmod_metis(&graph, nullptr, 0, 0, order.data(), &quiet.common);
    return ordered && threadRandom.seeds > before;
  }();
  return perThread;
}

} // namespace faceplan
