// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Runs Precompute on a worker thread as soon as its inputs are known, and beside it (its own
// worker) the large-deformation model's precompute (PrecomputeLargeDeformation) when it is asked
// for. A new request cancels the running one; wait() returns the system for the latest request
// only, so no stale result escapes.
#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>

namespace faceplan {

class BackgroundPrecompute {
public:
  BackgroundPrecompute() = default;
  ~BackgroundPrecompute();
  BackgroundPrecompute(const BackgroundPrecompute&) = delete;
  BackgroundPrecompute& operator=(const BackgroundPrecompute&) = delete;

  // Starts (or restarts) the precompute for `request`; returns at once.
  void start(PrecomputeRequest request, ProgressCallback progress = {});
  // Blocks until the latest request's precompute is done.
  Status wait(std::shared_ptr<const CondensedSystem>& system);
  // True once the latest request finished (successfully or not).
  bool ready() const;
  // Cancels the running precompute (wait() then reports "cancelled").
  void cancel();
  // Cancels and joins the worker; called for every instance when the process exits.
  void stopForExit();

  // The large-deformation precompute for `request` (replacing any earlier one; it is not
  // cancelled, only superseded: at most one runs, and a new start waits for it).
  void startLargeDeformation(PrecomputeRequest request, PrecomputedLargeDeformationOptions options);
  // Blocks until the latest large-deformation precompute is done (an error if none was started).
  Status waitLargeDeformation(std::shared_ptr<LargeDeformationSystem>& system);
  bool largeDeformationReady() const;

private:
  // One precompute's worker and what it publishes; a result is published only if no newer request
  // (a higher generation) came meanwhile.
  template <class System> struct Slot {
    explicit Slot(const char* none) : status(Status::Error(none)) {}
    std::thread worker;
    std::uint64_t generation = 0;
    bool finished = true;
    Status status;
    std::shared_ptr<System> system;
  };
  // Joins the slot's previous worker and runs `compute(system)` on a new one for the next
  // generation.
  template <class System, class Compute> void launch(Slot<System>& slot, Compute compute);
  template <class System> Status waitFor(Slot<System>& slot, std::shared_ptr<System>& system);
  void joinWorker();

  mutable std::mutex mutex_;
  std::condition_variable done_;
  std::shared_ptr<std::atomic<bool>> cancelFlag_;
  Slot<const CondensedSystem> linear_{"no precompute was started"};
  Slot<LargeDeformationSystem> large_{"no large-deformation precompute was started"};
};

} // namespace faceplan
