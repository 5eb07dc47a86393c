// Method choice and the Factorization stage.
#include "CondensedFEM/PrecomputeStages.h"

#include "CondensedFEM/MethodChoice.h"

#include <algorithm>
#include <limits>
#include <sstream>

namespace faceplan {

void ChooseSolveMethod(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  SystemInfo& info = sys.info;
  // The method needs only the analysis (the factor's size), so it is chosen before the numeric
  // factorization, which a backend may then do together with the response.
  sys.method = ChooseMethod(state.request.options, double(info.keptDofs), double(info.roiDofs),
                            double(state.segmentCoupling.cols()), info.factorNonzeros,
                            double(sys.factor.trailingDofs()), info.choiceReason);
  if (info.freeDofs == 0)
    sys.method = SolveMethod::CachedFactor;
  info.method = sys.method;
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
  const double rcond = sys.factor.reciprocalConditionEstimate();
  info.conditionEstimate = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  if (!state.backendResponse)
    state.report(0.6, "factorization");
  return Status::Ok();
}

} // namespace faceplan
