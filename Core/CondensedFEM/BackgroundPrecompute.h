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
  void joinWorker();

  mutable std::mutex mutex_;
  std::condition_variable done_;
  std::thread worker_;
  std::shared_ptr<std::atomic<bool>> cancelFlag_;
  std::uint64_t generation_ = 0;
  bool finished_ = true;
  Status status_ = Status::Error("no precompute was started");
  std::shared_ptr<const CondensedSystem> system_;

  std::thread largeWorker_;
  std::uint64_t largeGeneration_ = 0;
  bool largeFinished_ = true;
  Status largeStatus_ = Status::Error("no large-deformation precompute was started");
  std::shared_ptr<LargeDeformationSystem> large_;
};

} // namespace faceplan
