// SPDX-License-Identifier: BSD-3-Clause
// Common/HelperThreads: every part runs once, part 0 on the calling thread and the others on
// threads of their own that are kept from one call to the next; a call with more parts adds
// helpers, one with fewer leaves the rest idle; a part's exception reaches the caller, and the
// helpers serve the next call after it; a call from within a part runs its parts there; each
// calling thread has its own helpers (TSan runs this); a forked child, which has none of them,
// starts its own; the helpers carry a name, and one left without a part sleeps at once.
#include "Common/HelperThreads.h"
#include "Common/ParallelFor.h"

#include <atomic>
#include <condition_variable>
#include <gtest/gtest.h>
#include <mutex>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <chrono>
#include <csignal>
#include <ctime>
#include <pthread.h>
#include <sys/wait.h>
#include <unistd.h>

#if defined(__SANITIZE_THREAD__)
#define FACEPLAN_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define FACEPLAN_TSAN 1
#endif
#endif

using namespace faceplan;

namespace {

// The threads that ran each part of one call.
std::vector<std::thread::id> RunAndRecord(int parts) {
  std::vector<std::thread::id> ran(static_cast<size_t>(parts));
  std::vector<int> count(static_cast<size_t>(parts), 0);
  RunOnHelpers(parts, [&](int part) {
    ran[part] = std::this_thread::get_id();
    ++count[part];
  });
  for (int part = 0; part < parts; ++part)
    EXPECT_EQ(count[part], 1) << "part " << part;
  return ran;
}

} // namespace

TEST(HelperThreads, RunsEachPartOnceOnThreadsKeptFromCallToCall) {
  const std::vector<std::thread::id> first = RunAndRecord(3);
  EXPECT_EQ(first[0], std::this_thread::get_id());
  EXPECT_EQ(std::set<std::thread::id>(first.begin(), first.end()).size(), 3u);
  // The same helpers on the next call, more for a call with more parts, the same with fewer.
  EXPECT_EQ(RunAndRecord(3), first);
  const std::vector<std::thread::id> more = RunAndRecord(5);
  EXPECT_EQ(std::vector<std::thread::id>(more.begin(), more.begin() + 3), first);
  EXPECT_EQ(std::set<std::thread::id>(more.begin(), more.end()).size(), 5u);
  const std::vector<std::thread::id> fewer = RunAndRecord(2);
  EXPECT_EQ(fewer[1], first[1]);
  EXPECT_EQ(RunAndRecord(1)[0], std::this_thread::get_id());
  RunOnHelpers(0, [](int) { FAIL() << "no part to run"; });
}

TEST(HelperThreads, ManyCallsSumAsOneThreadWould) {
  std::vector<std::int64_t> values(100000);
  std::iota(values.begin(), values.end(), 1);
  for (int round = 0; round < 500; ++round) {
    const int parts = 1 + round % 4;
    std::vector<std::int64_t> sums(static_cast<size_t>(parts), 0);
    RunOnHelpers(parts, [&](int part) {
      for (size_t k = static_cast<size_t>(part); k < values.size(); k += parts)
        sums[part] += values[k];
    });
    ASSERT_EQ(std::accumulate(sums.begin(), sums.end(), std::int64_t{0}), 5000050000) << round;
  }
}

TEST(HelperThreads, APartsExceptionReachesTheCallerAndTheHelpersServeOn) {
  for (int thrower : {0, 1, 2}) {
    std::atomic<int> ran{0};
    EXPECT_THROW(RunOnHelpers(3,
                              [&](int part) {
                                ++ran;
                                if (part == thrower)
                                  throw std::runtime_error("part failed");
                              }),
                 std::runtime_error)
        << "thrown by part " << thrower;
    EXPECT_EQ(ran.load(), 3) << "the other parts still ran";
    EXPECT_EQ(RunAndRecord(3).size(), 3u);
  }
}

TEST(HelperThreads, ACallFromWithinAPartRunsItsPartsThere) {
  std::mutex mutex;
  std::vector<std::pair<int, int>> ran;
  RunOnHelpers(2, [&](int outer) {
    const std::thread::id here = std::this_thread::get_id();
    RunOnHelpers(3, [&](int inner) {
      std::lock_guard<std::mutex> lock(mutex);
      ran.emplace_back(outer, inner);
      if (outer == 0) // the calling thread's own call: inline
        EXPECT_EQ(std::this_thread::get_id(), here);
    });
  });
  EXPECT_EQ(ran.size(), 6u);
}

TEST(HelperThreads, EachCallingThreadHasItsOwnHelpers) {
  // Both callers stay alive until both have recorded: a thread id is reused once its thread
  // ends, so a crew that exited with its caller could share an id with the next one.
  std::vector<std::thread::id> a, b;
  std::mutex mutex;
  std::condition_variable bothRecorded;
  int recorded = 0;
  auto recordAndWait = [&](std::vector<std::thread::id>& into) {
    into = RunAndRecord(2);
    std::unique_lock<std::mutex> lock(mutex);
    ++recorded;
    bothRecorded.notify_all();
    bothRecorded.wait(lock, [&] { return recorded == 2; });
  };
  std::thread first([&] { recordAndWait(a); });
  std::thread second([&] { recordAndWait(b); });
  first.join();
  second.join();
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_NE(a[1], b[1]);
  // ParallelFor covers its range once, on them.
  std::vector<int> hits(10007, 0);
  ParallelFor(static_cast<std::int64_t>(hits.size()), 1, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t k = begin; k < end; ++k)
      ++hits[static_cast<size_t>(k)];
  });
  for (int h : hits)
    ASSERT_EQ(h, 1);
}

#ifdef __linux__
TEST(HelperThreads, HelpersAreNamedAndThoseWithoutAPartSleep) {
  // On a thread of its own: a fresh crew, whose helpers are numbered from this test's first call.
  std::thread([] {
    std::vector<pthread_t> helper(4);
    std::vector<std::string> name(4);
    RunOnHelpers(4, [&](int part) {
      helper[part] = pthread_self();
      char text[16] = {};
      pthread_getname_np(pthread_self(), text, sizeof text);
      name[part] = text;
    });
    for (int part = 1; part < 4; ++part)
      EXPECT_EQ(name[part], "faceplan-help") << "helper " << part;
    // Steps of two parts a millisecond apart: helpers 2 and 3 have no part in them. A helper that
    // stayed awake after each wake-up (2 ms) would spend most of the time on its core.
    auto cpuMs = [&](int part) {
      clockid_t clock;
      timespec t{};
      if (pthread_getcpuclockid(helper[part], &clock) != 0 || clock_gettime(clock, &t) != 0)
        return -1.0;
      return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
    };
    const double before2 = cpuMs(2), before3 = cpuMs(3);
    ASSERT_GE(before2, 0.0);
    ASSERT_GE(before3, 0.0);
    const auto start = std::chrono::steady_clock::now();
    std::atomic<int> ran{0};
    for (int step = 0; step < 60; ++step) {
      RunOnHelpers(2, [&](int) { ++ran; });
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const double wallMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(ran, 120);
    EXPECT_LT(cpuMs(2) - before2, 0.2 * wallMs) << "over " << wallMs << " ms";
    EXPECT_LT(cpuMs(3) - before3, 0.2 * wallMs) << "over " << wallMs << " ms";
  }).join();
}
#endif

TEST(HelperThreads, AForkedChildStartsItsOwn) {
#ifdef FACEPLAN_TSAN
  GTEST_SKIP() << "ThreadSanitizer does not support threads started after a fork";
#else
  ASSERT_EQ(RunAndRecord(2).size(), 2u); // this thread's crew exists before the fork
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    alarm(20); // a child waiting on the parent's helpers would hang: killed instead
    std::atomic<int> ran{0};
    RunOnHelpers(3, [&](int) { ++ran; });
    _exit(ran == 3 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child was killed (signal " << WTERMSIG(status) << ")";
  EXPECT_EQ(WEXITSTATUS(status), 0);
#endif
}
