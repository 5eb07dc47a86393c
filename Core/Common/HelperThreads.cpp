// SPDX-License-Identifier: BSD-3-Clause
#include "Common/HelperThreads.h"
#include "Common/WorkerThreads.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <unistd.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define FACEPLAN_PAUSE() _mm_pause()
#else
#define FACEPLAN_PAUSE() std::this_thread::yield()
#endif

namespace faceplan {

namespace {

// How long a helper stays awake after its part, and the caller waits awake for the helpers,
// before sleeping: longer than the serial gaps of one iteration (the L-BFGS recursion, the top of
// the factor's tree, a line-search step), short enough not to keep a core from other work for
// long. A helper that sleeps lets its core halt, and on a virtual machine waking a halted core
// waits for the hypervisor to schedule it again, which makes every parallel step after a gap slow.
constexpr std::chrono::microseconds kSpin(2000);

class Crew {
public:
  ~Crew() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    for (std::thread& t : threads_)
      t.join();
  }

  void run(int parts, const std::function<void(int)>& work) {
    const int helpers = parts - 1;
    while (static_cast<int>(threads_.size()) < helpers) {
      const int index = static_cast<int>(threads_.size());
      const std::uint64_t now = generation_.load(std::memory_order_acquire);
      threads_.emplace_back([this, index, now] { loop(index, now); });
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      work_ = &work;
      active_ = helpers;
      pending_.store(helpers, std::memory_order_relaxed);
      error_ = nullptr;
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    std::exception_ptr mine;
    try {
      work(0);
    } catch (...) {
      mine = std::current_exception();
    }
    const auto until = std::chrono::steady_clock::now() + kSpin;
    while (pending_.load(std::memory_order_acquire) > 0 && std::chrono::steady_clock::now() < until)
      FACEPLAN_PAUSE();
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return pending_.load(std::memory_order_acquire) == 0; });
    work_ = nullptr;
    if (mine)
      std::rethrow_exception(mine);
    if (error_)
      std::rethrow_exception(error_);
  }

private:
  void loop(int index, std::uint64_t seen) {
    NameThisThread("faceplan-help");
    bool hadPart = false;
    while (true) {
      // Awake for a while after a part, then asleep until the next step. A helper that had no
      // part in the last step (it had fewer parts than there are helpers: on a many-core machine
      // most steps) sleeps at once, or every step would keep all the cores busy.
      const auto until =
          std::chrono::steady_clock::now() + (hadPart ? kSpin : std::chrono::microseconds(0));
      while (generation_.load(std::memory_order_acquire) == seen &&
             std::chrono::steady_clock::now() < until)
        FACEPLAN_PAUSE();
      hadPart = false;
      const std::function<void(int)>* work = nullptr;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
        seen = generation_.load(std::memory_order_acquire);
        if (stop_)
          return;
        if (index >= active_)
          continue; // a step with fewer parts
        work = work_;
      }
      hadPart = true;
      std::exception_ptr error;
      try {
        (*work)(index + 1);
      } catch (...) {
        error = std::current_exception();
      }
      if (error) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_)
          error_ = error;
      }
      if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        std::lock_guard<std::mutex> lock(mutex_); // the caller may be between its check and wait
        done_.notify_one();
      }
    }
  }

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<int> pending_{0};
  const std::function<void(int)>* work_ = nullptr;
  int active_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

} // namespace

void RunOnHelpers(int parts, const std::function<void(int)>& work) {
  if (parts <= 1) {
    if (parts == 1)
      work(0);
    return;
  }
  thread_local std::unique_ptr<Crew> crew;
  thread_local bool running = false;
  if (running) { // a part that itself runs parts: serially, here
    for (int part = 0; part < parts; ++part)
      work(part);
    return;
  }
  // A process forked after the crew started has none of its threads: it starts its own (the
  // parent's crew, a copy of memory only, is left as it is).
  thread_local long owner = 0;
  const long process = static_cast<long>(getpid());
  if (crew && owner != process)
    (void)crew.release();
  if (!crew) {
    crew = std::make_unique<Crew>();
    owner = process;
  }
  running = true;
  try {
    crew->run(parts, work);
  } catch (...) {
    running = false;
    throw;
  }
  running = false;
}

} // namespace faceplan
