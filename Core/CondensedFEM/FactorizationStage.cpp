// SPDX-License-Identifier: BSD-3-Clause
// Method choice and the Factorization stage.
#include "CondensedFEM/PrecomputeStages.h"

#include "CondensedFEM/MemoryBudget.h"
#include "CondensedFEM/MethodChoice.h"

#include <algorithm>
#include <limits>
#include <sstream>

namespace faceplan {

Status ChooseSolveMethod(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  SystemInfo& info = sys.info;
  const PrecomputeOptions& options = state.request.options;
  // The method needs only the analysis (the factor's size), so it is chosen before the numeric
  // factorization, which a backend may then do together with the response. Both large
  // allocations are checked against the memory budget first.
  info.memoryBudgetBytes = MemoryBudgetBytes(options.memoryBudgetBytes);
  info.factorBytes = info.freeDofs > 0 ? sys.factor.factorBytes() : 0.0;
  if (info.factorBytes > info.memoryBudgetBytes)
    return Status::Error("the sparse factor would need about " + MegabyteText(info.factorBytes) +
                         ", more than the memory budget of " +
                         MegabyteText(info.memoryBudgetBytes) +
                         " (available memory unless memoryBudgetBytes is set): use a coarser mesh");
  PrecomputeOptions fitted = options;
  fitted.denseResponseBudgetBytes =
      std::min(options.denseResponseBudgetBytes, info.memoryBudgetBytes - info.factorBytes);
  sys.method = ChooseMethod(fitted, double(info.keptDofs), double(info.roiDofs),
                            double(state.segmentCoupling.cols()), info.factorNonzeros,
                            double(sys.factor.trailingDofs()), info.choiceReason);
  if (info.freeDofs == 0)
    sys.method = SolveMethod::CachedFactor;
  const double columns = sys.method == SolveMethod::DenseResponse ? double(info.roiDofs)
                         : sys.method == SolveMethod::RigidSegments
                             ? double(state.segmentCoupling.cols())
                             : 0.0;
  const double responseBytes = 8.0 * double(info.keptDofs) * columns;
  if (info.factorBytes + responseBytes > info.memoryBudgetBytes)
    return Status::Error("the " + std::string(MethodName(sys.method)) + " response would need " +
                         MegabyteText(responseBytes) + " beside the factor's " +
                         MegabyteText(info.factorBytes) + ", more than the memory budget of " +
                         MegabyteText(info.memoryBudgetBytes) +
                         ": use the CachedFactor or Auto method, or a smaller ROI or kept set");
  info.method = sys.method;
  return Status::Ok();
}

Status Factorize(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  SystemInfo& info = sys.info;
  if (info.freeDofs == 0)
    return Status::Ok();
  StageClock& clock = state.clock;
  ComputeBackend& backend = *state.backend;

  // Backend factorization + response (CUDA: numeric factorization and dense response on the GPU).
  // Whatever it does not deliver is done on the CPU, with a warning.
  if (sys.method == SolveMethod::DenseResponse && backend.providesFactorAndResponse()) {
    ComputeBackend::FactorResponseReport fr;
    const Status hook =
        backend.factorAndBuildResponse(sys.kff, sys.kfr, 3 * sys.layout.keptFree, sys.factor,
                                       sys.response, state.backendOperator, fr);
    bool ok = hook.ok;
    std::string hookError = hook.message;
    const bool factored = sys.factor.isFactorized();
    if (ok && !(fr.worstRelativeResidual <= sys.residualTolerance)) {
      std::ostringstream why;
      why << "its response's relative residual " << fr.worstRelativeResidual << " exceeds "
          << sys.residualTolerance;
      hookError = why.str();
      ok = false;
    }
    const double hookMs = clock.lapMs();
    const double factorMs = factored ? std::min(fr.factorizationMs, hookMs) : hookMs;
    state.time(Stage::Factorization).ms += factorMs;
    state.time(Stage::Condensation).ms += hookMs - factorMs;
    if (ok && factored && sys.response.rows() == info.keptDofs &&
        sys.response.cols() == info.roiDofs) {
      state.backendResponse = true;
      sys.responseResidual = fr.worstRelativeResidual;
      state.report(0.95, "dense response");
    } else {
      if (ok)
        hookError = "internal: the response or the factor is missing";
      state.status.warnings.push_back(
          backend.name() + " factorization/response failed (" + hookError + "); " +
          (factored ? "the response was built" : "factorized and built the response") +
          " on the CPU");
      sys.response.resize(0, 0);
      state.backendOperator.reset();
    }
  }
  if (!sys.factor.isFactorized()) {
    Status fs = sys.factor.factorize(sys.kff);
    if (!fs)
      return fs;
    state.time(Stage::Factorization).ms += clock.lapMs();
  }
  StageClock rcondClock;
  const double rcond = sys.factor.reciprocalConditionEstimate();
  info.conditionEstimateMs = rcondClock.elapsedMs();
  info.conditionEstimate = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  if (!state.backendResponse)
    state.report(0.6, "factorization");
  return Status::Ok();
}

} // namespace faceplan
