// SPDX-License-Identifier: BSD-3-Clause
// OpenBLAS's thread count after scopes that open and close on different threads.
#include "Common/BlasKernels.h"
#include "Common/BlasThreads.h"

#include <gtest/gtest.h>

#include <dlfcn.h>

#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

using namespace faceplan;

namespace {

int OpenBlasThreads() {
  auto get = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return get ? get() : -1;
}

// Steps of two threads taken in a fixed order.
class Turns {
public:
  void waitFor(int step) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return step_ >= step; });
  }
  void done(int step) {
    std::lock_guard<std::mutex> lock(mutex_);
    step_ = step;
    changed_.notify_all();
  }

private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int step_ = 0;
};

} // namespace

TEST(BlasThreads, InterleavedScopesOnTwoThreadsRestoreTheOriginalCount) {
  const int original = OpenBlasThreads();
  if (original <= 0)
    GTEST_SKIP() << "the BLAS in use is not OpenBLAS";
  Turns turns;
  // A opens, B opens, A closes, B closes: not nested, so each scope's own "previous" is wrong.
  std::thread a([&] {
    {
      ScopedBlasThreads scope(original + 2);
      turns.done(1);
      turns.waitFor(2);
    }
    turns.done(3);
  });
  std::thread b([&] {
    turns.waitFor(1);
    {
      ScopedBlasThreads scope(original + 1);
      turns.done(2);
      turns.waitFor(3);
    }
  });
  a.join();
  b.join();
  EXPECT_EQ(OpenBlasThreads(), original);
}

TEST(BlasThreads, NestedScopesGiveBackTheEnclosingCount) {
  const int original = OpenBlasThreads();
  if (original <= 0)
    GTEST_SKIP() << "the BLAS in use is not OpenBLAS";
  {
    ScopedBlasThreads outer(original + 2);
    {
      ScopedBlasThreads inner(1);
      EXPECT_EQ(OpenBlasThreads(), 1);
    }
    EXPECT_EQ(OpenBlasThreads(), original + 2);
  }
  EXPECT_EQ(OpenBlasThreads(), original);
}

// A pinned scope (a solve) keeps its count while another thread opens and closes a shared one (a
// precompute's single-threaded response), and shared scopes give way to the smallest request.
TEST(BlasThreads, APinnedScopeHoldsAgainstSharedScopesOnOtherThreads) {
  const int original = OpenBlasThreads();
  if (original <= 0)
    GTEST_SKIP() << "the BLAS in use is not OpenBLAS";
  Turns turns;
  int seenInsideShared = -1, seenAfterShared = -1;
  std::thread solver([&] {
    {
      ScopedBlasThreads pinned(original + 3, BlasScope::Pinned);
      turns.done(1);
      turns.waitFor(2);
      seenInsideShared = OpenBlasThreads();
      turns.done(3);
      turns.waitFor(4);
      seenAfterShared = OpenBlasThreads();
    }
    turns.done(5);
  });
  std::thread precompute([&] {
    turns.waitFor(1);
    {
      ScopedBlasThreads shared(1);
      turns.done(2);
      turns.waitFor(3);
    }
    turns.done(4);
  });
  solver.join();
  precompute.join();
  EXPECT_EQ(seenInsideShared, original + 3);
  EXPECT_EQ(seenAfterShared, original + 3);
  EXPECT_EQ(OpenBlasThreads(), original);
  {
    ScopedBlasThreads wide(original + 2);
    ScopedBlasThreads narrow(1);
    ScopedBlasThreads wider(original + 4);
    EXPECT_EQ(OpenBlasThreads(), 1);
  }
  EXPECT_EQ(OpenBlasThreads(), original);
}

// The suggestion: the CPU's widest kernels where OpenBLAS runs narrower ones; advice only where
// the user made no choice of their own.
TEST(BlasKernels, SuggestsTheCpusWidestKernels) {
  auto advise = [](const char* name, bool avx512, bool avx2, bool amd, bool chose) {
    BlasKernels k;
    k.name = name;
    k.cpuHasAvx512 = avx512;
    k.cpuHasAvx2 = avx2;
    k.amd = amd;
    k.userChose = chose;
    AdviseBlasKernels(k);
    return k;
  };
  // SSE3 kernels on an AVX-512 Intel CPU that OpenBLAS does not know.
  BlasKernels k = advise("Prescott", true, true, false, false);
  EXPECT_EQ(k.suggested, "SkylakeX");
  EXPECT_NE(k.advice.find("OPENBLAS_CORETYPE=SkylakeX"), std::string::npos) << k.advice;
  EXPECT_NE(k.advice.find("Prescott"), std::string::npos) << k.advice;
  // AVX2 kernels on an AVX-512 CPU.
  EXPECT_EQ(advise("Zen", true, true, true, false).suggested, "SkylakeX");
  EXPECT_EQ(advise("Haswell", true, true, false, false).suggested, "SkylakeX");
  // Pre-AVX2 kernels on AVX2 CPUs: Intel's and AMD's AVX2 kernels.
  EXPECT_EQ(advise("Nehalem", false, true, false, false).suggested, "Haswell");
  EXPECT_EQ(advise("Sandybridge", false, true, true, false).suggested, "Zen");
  // The CPU's own kernels, or a CPU without AVX2: nothing to suggest.
  EXPECT_TRUE(advise("SkylakeX", true, true, false, false).suggested.empty());
  EXPECT_TRUE(advise("Cooperlake", true, true, false, false).suggested.empty());
  EXPECT_TRUE(advise("Zen", false, true, true, false).suggested.empty());
  EXPECT_TRUE(advise("Haswell", false, true, false, false).suggested.empty());
  EXPECT_TRUE(advise("Prescott", false, false, false, false).suggested.empty());
  EXPECT_TRUE(advise("", true, true, false, false).suggested.empty()); // not OpenBLAS
  // A user's own choice is theirs: the suggestion stays, the advice goes.
  k = advise("Haswell", true, true, false, true);
  EXPECT_EQ(k.suggested, "SkylakeX");
  EXPECT_TRUE(k.advice.empty());
}

// The process's own report names OpenBLAS's choice (the tests link OpenBLAS) and reads the
// user's choice from the environment.
TEST(BlasKernels, DescribesThisProcess) {
  const BlasKernels k = DescribeBlasKernels();
  if (k.name.empty())
    GTEST_SKIP() << "the BLAS in this process is not OpenBLAS";
  EXPECT_EQ(k.userChose, std::getenv("OPENBLAS_CORETYPE") != nullptr);
  EXPECT_EQ(k.advice.empty(), k.suggested.empty() || k.userChose) << k.name;
  if (k.cpuHasAvx512)
    EXPECT_TRUE(k.cpuHasAvx2);
}
