// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/BackgroundPrecompute.h"

#include <cstdlib>
#include <set>

namespace faceplan {

namespace {

// Every instance with a worker. When the process exits while a precompute runs (the host
// application quits from a callback, with the owning filter never destroyed), the worker is
// cancelled and joined before the libraries it uses (BLAS, CHOLMOD) are torn down; otherwise it
// crashes or hangs inside them.
struct LiveInstances {
  std::mutex mutex;
  std::set<BackgroundPrecompute*> instances;
};

// Never destroyed: an owner may be destroyed by another library's static teardown after exit's
// handlers have run.
LiveInstances& Live() {
  static LiveInstances* live = [] {
    auto* instances = new LiveInstances;
    std::atexit([] {
      std::lock_guard<std::mutex> lock(Live().mutex);
      for (BackgroundPrecompute* b : Live().instances)
        b->stopForExit();
    });
    return instances;
  }();
  return *live;
}

} // namespace

BackgroundPrecompute::~BackgroundPrecompute() {
  {
    std::lock_guard<std::mutex> lock(Live().mutex);
    Live().instances.erase(this);
  }
  cancel();
  joinWorker();
}

void BackgroundPrecompute::stopForExit() {
  cancel();
  joinWorker();
  std::shared_ptr<LargeDeformationSystem> large;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    large = large_;
  }
  if (large)
    StopRefactorization(*large);
}

void BackgroundPrecompute::joinWorker() {
  if (worker_.joinable())
    worker_.join();
  if (largeWorker_.joinable())
    largeWorker_.join();
}

void BackgroundPrecompute::startLargeDeformation(PrecomputeRequest request,
                                                 PrecomputedLargeDeformationOptions options) {
  {
    std::lock_guard<std::mutex> lock(Live().mutex);
    Live().instances.insert(this);
  }
  if (largeWorker_.joinable())
    largeWorker_.join();
  std::uint64_t generation;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation = ++largeGeneration_;
    largeFinished_ = false;
    large_.reset();
  }
  largeWorker_ =
      std::thread([this, generation, request = std::move(request), options = std::move(options)] {
        std::shared_ptr<LargeDeformationSystem> system;
        Status status = PrecomputeLargeDeformation(request, options, system);
        std::lock_guard<std::mutex> lock(mutex_);
        if (generation != largeGeneration_)
          return;
        largeStatus_ = status;
        large_ = status ? system : nullptr;
        largeFinished_ = true;
        done_.notify_all();
      });
}

Status BackgroundPrecompute::waitLargeDeformation(std::shared_ptr<LargeDeformationSystem>& system) {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return largeFinished_; });
  system = large_;
  return largeStatus_;
}

bool BackgroundPrecompute::largeDeformationReady() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return largeFinished_;
}

void BackgroundPrecompute::start(PrecomputeRequest request, ProgressCallback progress) {
  {
    std::lock_guard<std::mutex> lock(Live().mutex);
    Live().instances.insert(this);
  }
  cancel();
  // The old worker sees its cancel flag at its next stage boundary; waiting for it keeps at most
  // one precompute (and its memory) alive.
  if (worker_.joinable())
    worker_.join();
  auto flag = std::make_shared<std::atomic<bool>>(false);
  std::uint64_t generation;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation = ++generation_;
    cancelFlag_ = flag;
    finished_ = false;
    system_.reset();
  }
  worker_ = std::thread([this, flag, generation, request = std::move(request), progress] {
    std::shared_ptr<const CondensedSystem> system;
    Status status = Precompute(request, system, flag.get(), progress);
    std::lock_guard<std::mutex> lock(mutex_);
    if (generation != generation_)
      return; // superseded: never publish a stale result
    status_ = status;
    system_ = status ? system : nullptr;
    finished_ = true;
    done_.notify_all();
  });
}

Status BackgroundPrecompute::wait(std::shared_ptr<const CondensedSystem>& system) {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return finished_; });
  system = system_;
  return status_;
}

bool BackgroundPrecompute::ready() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return finished_;
}

void BackgroundPrecompute::cancel() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (cancelFlag_)
    cancelFlag_->store(true);
  if (!finished_) {
    // Whoever waits gets "cancelled" unless a new start() supersedes this request.
    ++generation_;
    status_ = Status::Error("cancelled");
    system_.reset();
    finished_ = true;
    done_.notify_all();
  }
}

} // namespace faceplan
