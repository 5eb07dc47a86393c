// SPDX-License-Identifier: BSD-3-Clause
// WorkerThreads: the cap and FACEPLAN_THREADS. CTest runs this executable twice, without the
// variable and with FACEPLAN_THREADS=1 (FACEPLAN_EXPECT_ONE_THREAD=1 tells it which).
#include "Common/WorkerThreads.h"

#include <cstdlib>
#include <gtest/gtest.h>
#include <thread>

using namespace faceplan;

TEST(WorkerThreads, FollowsTheCapTheCoresAndTheEnvironment) {
  EXPECT_EQ(WorkerThreads(1), 1);
  EXPECT_EQ(WorkerThreads(0), 1);
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  if (std::getenv("FACEPLAN_EXPECT_ONE_THREAD"))
    EXPECT_EQ(WorkerThreads(16), 1);
  else
    EXPECT_EQ(WorkerThreads(16), std::min(cores, 16));
}
