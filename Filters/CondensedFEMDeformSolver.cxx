// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformSolver.h"

#include "CondensedFEM/RequestIdentity.h"
#include "CondensedFEM/Verify.h"
#ifdef FACEPLAN_HAS_CUDA
#include "CudaBackend.h"
#endif

#include <atomic>
#include <chrono>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

namespace faceplan {
namespace fem_filter {

void ApplyMethodAndOrder(const Settings& settings, PrecomputeOptions& options) {
  switch (settings.methodChoice()) {
  case MethodChoice::DenseResponse:
    options.method = SolveMethod::DenseResponse;
    break;
  case MethodChoice::CachedFactor:
    options.method = SolveMethod::CachedFactor;
    break;
  default:
    options.method = SolveMethod::Auto;
    break;
  }
  switch (static_cast<ElementOrderChoice>(settings.elementOrder)) {
  case ElementOrderChoice::Quadratic:
    options.elementOrder = ElementOrder::Quadratic;
    break;
  case ElementOrderChoice::QuadraticNodalPressure:
    options.elementOrder = ElementOrder::QuadraticNodalPressure;
    break;
  default:
    options.elementOrder = ElementOrder::Linear;
    break;
  }
}

void Solver::chooseBackend(const Settings& settings, PrecomputeOptions& options,
                           std::vector<std::string>& notes) {
  if (static_cast<BackendChoice>(settings.backend) == BackendChoice::CPU)
    return;
  if (!cudaProbed_) {
    cudaProbed_ = true;
#ifdef FACEPLAN_HAS_CUDA
    const Status made = cuda::MakeCudaBackend(cudaBackend_);
    if (!made)
      cudaUnavailable_ = made.message;
#else
    cudaUnavailable_ = "this build has no CUDA backend";
#endif
  }
  if (cudaBackend_)
    options.backend = cudaBackend_;
  else if (static_cast<BackendChoice>(settings.backend) == BackendChoice::CUDA)
    notes.push_back("Backend CUDA is not available (" + cudaUnavailable_ + "); using the CPU");
}

void Solver::waitForBackgroundWork() {
  if (!haveLarge_)
    return;
  std::shared_ptr<LargeDeformationSystem> system;
  if (background_.waitLargeDeformation(system) && system)
    WaitForRefactorization(*system);
}

void Solver::startLargeDeformation(const PrecomputeRequest& given, const Settings& settings,
                                   const std::shared_ptr<ComputeBackend>& backend) {
  if (haveLarge_ && largeLiftOff_ == settings.liftOff && largeRequest_.options.backend == backend &&
      SameInputs(given, largeRequest_))
    return;
  largeRequest_ = given;
  largeRequest_.options = PrecomputeOptions(); // linear cells
  // The backend runs the forces, substitutions and tangent products it can.
  largeRequest_.options.backend = backend;
  PrecomputedLargeDeformationOptions options;
  options.slidingLiftOff = settings.liftOff;
  background_.startLargeDeformation(largeRequest_, options);
  haveLarge_ = true;
  largeLiftOff_ = settings.liftOff;
  largeState_ = LargeDeformationState();
}

Status Solver::runLargeDeformation(const PrecomputeRequest& given, const PrecomputeOptions& options,
                                   const SolveInput& input, const Settings& settings,
                                   const std::function<void(double)>& progress,
                                   SolveOutcome& outcome) {
  outcome.largeDeformation = true;
  outcome.model = "NeoHookean";
  outcome.result = SolveResult();
  if (settings.newtonSolver()) {
    // Newton iterations on the whole mesh: no precompute to cache, nothing to hand to a worker.
    outcome.newton = true;
    PrecomputeRequest request = given;
    request.options = options;
    LargeDeformationOptions largeOptions;
    largeOptions.slidingLiftOff = settings.liftOff;
    largeOptions.progress = progress;
    return SolveLargeDeformation(request, input, largeOptions, outcome.result,
                                 outcome.largeDeformationReport);
  }
  startLargeDeformation(given, settings, options.backend);
  while (!background_.largeDeformationReady()) {
    if (progress)
      progress(0.5);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::shared_ptr<LargeDeformationSystem> system;
  Status status = background_.waitLargeDeformation(system);
  if (!status) {
    haveLarge_ = false; // retried next time
    return status;
  }
  const StageTimings precompute = PrecomputeTimings(*system);
  if (largeState_.system != system.get())
    largeState_ = LargeDeformationState();
  const bool fresh = !largeState_.valid();
  LargeDeformationState next;
  status =
      SolvePrecomputedLargeDeformation(*system, input, &largeState_, outcome.result,
                                       outcome.precomputedReport, &next, settings.iterationLimit);
  // A stopped iterate is no state to start from: the next update starts from the last converged.
  if (!outcome.precomputedReport.stoppedAtLimit)
    largeState_ = next;
  if (!status)
    return status;
  if (outcome.precomputedReport.stoppedAtLimit) {
    std::ostringstream note;
    note << "stopped after " << outcome.precomputedReport.iterations
         << " quasi-Newton iterations (QuasiNewtonIterationLimit) at relative residual "
         << outcome.result.relativeResidual << ": this is not the equilibrium";
    outcome.solverNote = note.str();
    outcome.notes.push_back(outcome.solverNote);
  }
  if (!outcome.precomputedReport.deviceNote.empty())
    outcome.notes.push_back("the large-deformation solve's backend: " +
                            outcome.precomputedReport.deviceNote);
  outcome.precomputeMs = precompute[Stage::Total].ms;
  outcome.freshPrecompute = outcome.freshPrecompute || fresh;
  if (outcome.precomputedReport.fellBack) {
    outcome.newton = true;
    outcome.largeDeformationReport = outcome.precomputedReport.newton;
    outcome.solverNote = "the precomputed solve did not converge (" +
                         outcome.precomputedReport.fallbackReason + "): solved by Newton";
  }
  return status;
}

Status Solver::run(const PrecomputeRequest& given, const SolveInput& input,
                   const Settings& settings, const std::function<void(double)>& progress,
                   SolveOutcome& outcome) {
  outcome = SolveOutcome();
  PrecomputeOptions options = given.options;
  ApplyMethodAndOrder(settings, options);
  if (settings.fullReference() && options.elementOrder != ElementOrder::Linear) {
    outcome.notes.push_back(
        "the FullReference method supports linear elements only: solved with linear elements");
    options.elementOrder = ElementOrder::Linear;
  }
  const ModelChoice model = settings.modelChoice();
  chooseBackend(settings, options, outcome.notes);
  // The request as solved: the given inputs with these options. Made only where a path keeps it or
  // is slow anyway (a new precompute, the reference and large-deformation solves, Verify): an edit
  // that reuses the precompute compares, and copies nothing (at ~100k cells the mesh and materials
  // copied on every edit cost ~0.3 ms, most of it page faults).
  auto withOptions = [&given, &options]() {
    PrecomputeRequest request = given;
    request.options = options;
    return request;
  };
  // LiftOff is on by default: where the linear model runs with sliding tissue it is that model's
  // own limit, said in its note rather than warned about on every update.
  const bool linearIgnoresLiftOff = settings.liftOff && !given.sets.sliding.empty();
  const char* liftOffNote =
      "LiftOff applies to Model NeoHookean only: the linear model keeps sliding tissue on the bone";

  Status status;
  if (model == ModelChoice::NeoHookean) {
    outcome.modelNote = "Model NeoHookean (as set)";
    status = runLargeDeformation(given, options, input, settings, progress, outcome);
  } else {
    if (settings.fullReference()) {
      status = SolveFullReference(withOptions(), input, outcome.result);
    } else {
      auto fraction = std::make_shared<std::atomic<double>>(0.0);
      if (!haveRequest_ || !SameOptions(options, lastRequest_.options) ||
          !SameInputs(given, lastRequest_)) {
        lastRequest_ = withOptions();
        background_.start(lastRequest_, [fraction](double f, const char*) { fraction->store(f); });
        haveRequest_ = true;
        outcome.freshPrecompute = true;
        ++precomputeCount_;
      }
      // Auto may need the large-deformation model: its precompute runs beside the linear one.
      if (model == ModelChoice::Auto && !settings.newtonSolver() &&
          options.elementOrder == ElementOrder::Linear)
        startLargeDeformation(given, settings, options.backend);
      // The worker's progress is reported from this (the pipeline's) thread.
      while (!background_.ready()) {
        if (progress)
          progress(fraction->load());
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      std::shared_ptr<const CondensedSystem> system;
      status = background_.wait(system);
      if (!status) {
        haveRequest_ = false; // a failed precompute is retried next time
        return status;
      }
      // The precompute's findings (slivers, fallbacks) are reported once, not again on every edit.
      if (outcome.freshPrecompute)
        for (const auto& w : status.warnings)
          outcome.notes.push_back(w);
      status = Solve(*system, input, outcome.result);
      const SystemInfo info = Describe(*system);
      outcome.precomputeMs = info.precomputeTimings[Stage::Total].ms;
      if (outcome.freshPrecompute)
        for (int k = 0; k < kNumStages; ++k)
          if (info.precomputeTimings.stages[k].ms > 0.0)
            outcome.result.timings.stages[k].reused = false;
      outcome.result.timings[Stage::Total].reused = false;
    }
    if (status && model == ModelChoice::Auto) {
      // Linear while its largest strain is within the small-strain limit, else large deformation.
      const double limit = options.strainWarningLimit, strain = outcome.result.largestStrain;
      std::ostringstream why;
      why << "Auto: the linear result's largest strain " << 100.0 * strain << " % is ";
      if (!(limit > 0.0)) {
        outcome.modelNote = "Auto: the small-strain check is off (StrainWarningLimit 0): linear";
      } else if (strain <= limit && outcome.result.invertedCells == 0) {
        why << "within the small-strain limit " << 100.0 * limit << " %: linear";
        if (linearIgnoresLiftOff)
          why << " (" << liftOffNote << ")";
        outcome.modelNote = why.str();
      } else if (options.elementOrder != ElementOrder::Linear) {
        why << "beyond the small-strain limit " << 100.0 * limit
            << " %, but the neo-Hookean model takes ElementOrder Linear only: linear";
        outcome.modelNote = why.str();
      } else {
        why << "beyond the small-strain limit " << 100.0 * limit << " %: NeoHookean";
        if (settings.verify)
          why << " (Verify compares linear results: not run)";
        outcome.modelNote = why.str();
        const bool freshLinear = outcome.freshPrecompute;
        std::vector<std::string> notes = outcome.notes;
        status = runLargeDeformation(given, options, input, settings, progress, outcome);
        outcome.freshPrecompute = outcome.freshPrecompute || freshLinear;
        outcome.notes = notes;
      }
    } else if (status) {
      outcome.modelNote = "Model LinearElastic (as set)";
      if (linearIgnoresLiftOff)
        outcome.modelNote += std::string("; ") + liftOffNote;
    }
  }
  if (!status)
    return status;
  for (const auto& w : status.warnings) // the solve's (large strain, inversion)
    outcome.notes.push_back(w.find("small-strain range") != std::string::npos
                                ? w + " (Model NeoHookean solves for large deformations)"
                                : w);

  if (settings.verify && !outcome.largeDeformation) {
    const Status verified =
        VerifyAgainstReference(withOptions(), input, outcome.result, outcome.verifyError);
    if (!verified)
      return verified;
  }
  return Status::Ok();
}

} // namespace fem_filter
} // namespace faceplan
