// SPDX-License-Identifier: BSD-3-Clause
// The background precompute under concurrency (run under ThreadSanitizer by `scripts/sanitize
// thread`): restarts and cancels in quick succession, solves running while a precompute runs,
// waiters on other threads, and the owner destroyed while its precompute runs.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/BackgroundPrecompute.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

SolveResult SolveOrFail(const CondensedSystem& system, const SolveInput& input) {
  SolveResult result;
  const Status s = Solve(system, input, result);
  EXPECT_TRUE(s.ok) << s.message;
  return result;
}

} // namespace

TEST(BackgroundPrecomputeConcurrency, RapidRestartsAndCancelsPublishOnlyTheLastRequest) {
  const PrecomputeRequest big = ShellRequest(6, 3);
  const PrecomputeRequest last = ShellRequest(3, 2, 5000.0, 0.3);
  BackgroundPrecompute background;
  for (int i = 0; i < 12; ++i) {
    background.start(big);
    if (i % 3 == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    if (i % 2 == 0)
      background.cancel();
  }
  background.start(last);
  std::shared_ptr<const CondensedSystem> system;
  const Status s = background.wait(system);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(Describe(*system).keptDofs, 3LL * static_cast<long long>(last.sets.kept.size()));
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(last);
  SolveResult reference;
  ASSERT_TRUE(SolveFullReference(last, input, reference).ok);
  EXPECT_LT(RelativeMaxDifference(SolveOrFail(*system, input).keptDisplacement,
                                  reference.keptDisplacement),
            1e-10);
}

TEST(BackgroundPrecomputeConcurrency, SolvesRunWhileAPrecomputeRuns) {
  // A finished system serves solves on several threads while the next precompute runs.
  for (SolveMethod method : {SolveMethod::DenseResponse, SolveMethod::CachedFactor}) {
    PrecomputeRequest first = ShellRequest(4, 2);
    first.options.method = method;
    std::shared_ptr<const CondensedSystem> system;
    ASSERT_TRUE(Precompute(first, system).ok);
    SolveInput input;
    input.movableDisplacement = SmoothRoiField(first);
    const SolveResult expected = SolveOrFail(*system, input);

    BackgroundPrecompute background;
    background.start(ShellRequest(6, 3));
    std::vector<std::thread> solvers;
    std::atomic<int> mismatches{0};
    for (int t = 0; t < 3; ++t) {
      solvers.emplace_back([&] {
        for (int k = 0; k < 4; ++k) {
          const SolveResult r = SolveOrFail(*system, input);
          if (!(r.keptDisplacement - expected.keptDisplacement).isZero(0.0))
            ++mismatches;
        }
      });
    }
    for (auto& t : solvers)
      t.join();
    std::shared_ptr<const CondensedSystem> next;
    EXPECT_TRUE(background.wait(next).ok);
    EXPECT_EQ(mismatches.load(), 0) << MethodName(method);
  }
}

TEST(BackgroundPrecomputeConcurrency, WaitersOnOtherThreadsSeeTheLatestRequestOrCancelled) {
  const PrecomputeRequest first = ShellRequest(6, 3);
  const PrecomputeRequest second = ShellRequest(3, 2);
  BackgroundPrecompute background;
  background.start(first);
  std::atomic<int> finishedWaiters{0};
  std::vector<std::thread> waiters;
  for (int t = 0; t < 2; ++t) {
    waiters.emplace_back([&] {
      std::shared_ptr<const CondensedSystem> system;
      const Status s = background.wait(system);
      // Either the first request was superseded ("cancelled") or the waiter saw the second's
      // system.
      if (s.ok) {
        EXPECT_EQ(Describe(*system).keptDofs,
                  3LL * static_cast<long long>(second.sets.kept.size()));
      } else {
        EXPECT_EQ(s.message, "cancelled");
      }
      ++finishedWaiters;
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  background.start(second);
  for (auto& t : waiters)
    t.join();
  EXPECT_EQ(finishedWaiters.load(), 2);
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(background.wait(system).ok);
  EXPECT_EQ(Describe(*system).keptDofs, 3LL * static_cast<long long>(second.sets.kept.size()));
}

TEST(BackgroundPrecomputeConcurrency, OwnerDestroyedWhileItsPrecomputeRuns) {
  // The destructor cancels and joins: it returns, the progress callback is never called after it,
  // and nothing the worker touches outlives its owner.
  for (int delayMs : {0, 1, 5, 20}) {
    auto calls = std::make_shared<std::atomic<int>>(0);
    auto destroyed = std::make_shared<std::atomic<bool>>(false);
    auto lateCalls = std::make_shared<std::atomic<int>>(0);
    {
      auto background = std::make_unique<BackgroundPrecompute>();
      background->start(ShellRequest(6, 3), [calls, destroyed, lateCalls](double, const char*) {
        ++*calls;
        if (destroyed->load())
          ++*lateCalls;
      });
      std::this_thread::sleep_for(std::chrono::milliseconds(delayMs));
      background.reset();
      destroyed->store(true);
    }
    EXPECT_EQ(lateCalls->load(), 0) << "delay " << delayMs << " ms";
  }
}
