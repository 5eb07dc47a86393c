// SPDX-License-Identifier: BSD-3-Clause
// The per-thread METIS random generator (Core/SparseSolver/MetisRandom.h): it must be the one
// libmetis reaches in this process, and it must give the sequence the C library's rand() gives, so
// that orderings equal those METIS made on the shared generator alone.
#include "SparseSolver/MetisRandom.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <thread>
#include <vector>

extern "C" {
void gk_randinit(uint64_t seed);
uint32_t gk_randint32(void);
uint64_t gk_randint64(void);
}

namespace faceplan {
namespace {

// Debian's METIS calls its generator through its PLT, and Core's definitions come first in the
// lookup order of this test program, as in the plugin: if this fails, every METIS call takes
// MetisMutex and the dissection runs one call at a time (correct, slower).
TEST(MetisRandom, LibmetisDrawsFromThePerThreadGenerator) {
  EXPECT_TRUE(MetisRandomIsPerThread());
}

TEST(MetisRandom, GivesTheSequenceOfRandAfterTheSameSeed) {
  for (unsigned int seed : {1u, 4321u, 123456789u}) {
    std::srand(seed);
    gk_randinit(seed);
    for (int k = 0; k < 1000; ++k)
      ASSERT_EQ(gk_randint32(), static_cast<uint32_t>(std::rand()))
          << "seed " << seed << " draw " << k;
    const uint64_t high = static_cast<uint32_t>(std::rand());
    const uint64_t low = static_cast<uint32_t>(std::rand());
    EXPECT_EQ(gk_randint64(), (high << 32) | low);
  }
}

TEST(MetisRandom, ThreadsDrawTheirOwnSequences) {
  gk_randinit(4321);
  std::vector<uint32_t> alone(5000);
  for (uint32_t& value : alone)
    value = gk_randint32();
  constexpr int kThreads = 4;
  std::vector<std::vector<uint32_t>> drawn(kThreads, std::vector<uint32_t>(alone.size()));
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t]() {
      gk_randinit(4321);
      for (uint32_t& value : drawn[t])
        value = gk_randint32();
    });
  for (std::thread& thread : threads)
    thread.join();
  for (int t = 0; t < kThreads; ++t)
    EXPECT_EQ(drawn[t], alone) << "thread " << t;
}

} // namespace
} // namespace faceplan
