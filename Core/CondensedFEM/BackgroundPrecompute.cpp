// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/BackgroundPrecompute.h"

#include "Common/WorkerThreads.h"

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
    large = large_.system;
  }
  if (large)
    StopRefactorization(*large);
}

void BackgroundPrecompute::joinWorker() {
  if (linear_.worker.joinable())
    linear_.worker.join();
  if (large_.worker.joinable())
    large_.worker.join();
}

template <class System, class Compute>
void BackgroundPrecompute::launch(Slot<System>& slot, Compute compute) {
  {
    std::lock_guard<std::mutex> lock(Live().mutex);
    Live().instances.insert(this);
  }
  // Waiting for the previous worker keeps at most one precompute (and its memory) alive per slot.
  if (slot.worker.joinable())
    slot.worker.join();
  std::uint64_t generation;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation = ++slot.generation;
    slot.finished = false;
    slot.system.reset();
  }
  slot.worker = std::thread([this, &slot, generation, compute = std::move(compute)] {
    NameThisThread("faceplan-pre");
    std::shared_ptr<System> system;
    Status status = compute(system);
    std::lock_guard<std::mutex> lock(mutex_);
    if (generation != slot.generation)
      return; // superseded: never publish a stale result
    slot.status = status;
    slot.system = status ? system : nullptr;
    slot.finished = true;
    done_.notify_all();
  });
}

template <class System>
Status BackgroundPrecompute::waitFor(Slot<System>& slot, std::shared_ptr<System>& system) {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&slot] { return slot.finished; });
  system = slot.system;
  return slot.status;
}

void BackgroundPrecompute::startLargeDeformation(PrecomputeRequest request,
                                                 PrecomputedLargeDeformationOptions options) {
  launch(large_, [request = std::move(request),
                  options = std::move(options)](std::shared_ptr<LargeDeformationSystem>& system) {
    return PrecomputeLargeDeformation(request, options, system);
  });
}

Status BackgroundPrecompute::waitLargeDeformation(std::shared_ptr<LargeDeformationSystem>& system) {
  return waitFor(large_, system);
}

bool BackgroundPrecompute::largeDeformationReady() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return large_.finished;
}

void BackgroundPrecompute::start(PrecomputeRequest request, ProgressCallback progress) {
  // The old worker sees its cancel flag at its next stage boundary.
  cancel();
  auto flag = std::make_shared<std::atomic<bool>>(false);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelFlag_ = flag;
  }
  launch(linear_, [flag, request = std::move(request),
                   progress](std::shared_ptr<const CondensedSystem>& system) {
    return Precompute(request, system, flag.get(), progress);
  });
}

Status BackgroundPrecompute::wait(std::shared_ptr<const CondensedSystem>& system) {
  return waitFor(linear_, system);
}

bool BackgroundPrecompute::ready() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return linear_.finished;
}

void BackgroundPrecompute::cancel() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (cancelFlag_)
    cancelFlag_->store(true);
  if (!linear_.finished) {
    // Whoever waits gets "cancelled" unless a new start() supersedes this request.
    ++linear_.generation;
    linear_.status = Status::Error("cancelled");
    linear_.system.reset();
    linear_.finished = true;
    done_.notify_all();
  }
}

} // namespace faceplan
