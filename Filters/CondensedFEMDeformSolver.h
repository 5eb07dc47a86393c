// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Step 4 of CondensedFEMDeform: the backend, the cached background precompute and the solve.
// Keeps the last request: when only the prescribed values change the precompute is reused.
// Private to FacePlan::Filters.
#include "CondensedFEMDeformSettings.h"

#include "CondensedFEM/BackgroundPrecompute.h"
#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/LargeDeformation.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"

#include <functional>
#include <string>
#include <vector>

namespace faceplan {
namespace fem_filter {

struct SolveOutcome {
  SolveResult result;
  bool freshPrecompute = false;   // this update started a precompute
  double precomputeMs = 0.0;      // the cached precompute's total
  double verifyError = -1.0;      // with Verify: largest relative difference to the reference
  std::vector<std::string> notes; // warnings for the user (precompute findings once, then solve's)
  std::string model = "LinearElastic";                 // the model that ran
  std::string modelNote;                               // why (Auto's choice, or as set)
  bool largeDeformation = false;                       // the neo-Hookean model ran
  bool newton = false;                                 // ... by Newton (as set, or as the fallback)
  std::string solverNote;                              // why Newton ran when Precomputed was set
  LargeDeformationReport largeDeformationReport;       // Newton's
  PrecomputedLargeDeformationReport precomputedReport; // the precomputed solve's
};

class Solver {
public:
  // `progress` is called on the calling thread with a fraction in [0, 1] while the worker runs.
  // `request`: the inputs; its options are adjusted to the settings here. An edit that keeps the
  // precompute compares the request with the last one and copies nothing.
  Status run(const PrecomputeRequest& request, const SolveInput& input, const Settings& settings,
             const std::function<void(double)>& progress, SolveOutcome& outcome);
  int precomputeCount() const { return precomputeCount_; }
  // Blocks until the large-deformation precompute and its background work (the refactorization
  // after a solve, the corrections of the state ahead) are done; at once where there is none.
  void waitForBackgroundWork();

private:
  void chooseBackend(const Settings& settings, PrecomputeOptions& options,
                     std::vector<std::string>& notes);
  // Starts the large-deformation precompute for these inputs unless the one kept is for them.
  void startLargeDeformation(const PrecomputeRequest& given, const Settings& settings,
                             const std::shared_ptr<ComputeBackend>& backend);
  Status runLargeDeformation(const PrecomputeRequest& given, const PrecomputeOptions& options,
                             const SolveInput& input, const Settings& settings,
                             const std::function<void(double)>& progress, SolveOutcome& outcome);

  BackgroundPrecompute background_;
  PrecomputeRequest lastRequest_;
  bool haveRequest_ = false;
  int precomputeCount_ = 0;
  // The large-deformation precompute's request (linear options) and lift-off, and the last
  // converged state, from which the next solve starts.
  PrecomputeRequest largeRequest_;
  bool haveLarge_ = false, largeLiftOff_ = false;
  LargeDeformationState largeState_;
  std::shared_ptr<ComputeBackend> cudaBackend_;
  std::string cudaUnavailable_;
  bool cudaProbed_ = false;
};

// Core's options for the filter's Method and ElementOrder.
void ApplyMethodAndOrder(const Settings& settings, PrecomputeOptions& options);

} // namespace fem_filter
} // namespace faceplan
