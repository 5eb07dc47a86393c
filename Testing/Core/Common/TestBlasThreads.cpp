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

// The kernel report names OpenBLAS's choice (the tests link OpenBLAS) and gives advice only while
// AVX2 kernels run on an AVX-512 CPU and the user made no choice of their own.
TEST(BlasKernels, AdviceOnlyForAvx2KernelsOnAnAvx512CpuWithoutAUserChoice) {
  const char* previous = std::getenv("OPENBLAS_CORETYPE");
  const std::string saved = previous ? previous : "";
  unsetenv("OPENBLAS_CORETYPE");
  const BlasKernels unset = DescribeBlasKernels();
  if (unset.name.empty())
    GTEST_SKIP() << "the BLAS in this process is not OpenBLAS";
  const bool avx2 = unset.name == "Haswell" || unset.name == "Zen";
  EXPECT_EQ(!unset.advice.empty(), avx2 && unset.cpuHasAvx512) << unset.name;
  if (!unset.advice.empty())
    EXPECT_NE(unset.advice.find("OPENBLAS_CORETYPE=SkylakeX"), std::string::npos);
  setenv("OPENBLAS_CORETYPE", "Haswell", 1); // a user's own choice is theirs
  EXPECT_TRUE(DescribeBlasKernels().advice.empty());
  if (previous)
    setenv("OPENBLAS_CORETYPE", saved.c_str(), 1);
  else
    unsetenv("OPENBLAS_CORETYPE");
}
