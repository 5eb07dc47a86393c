// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/CondensedFEM.h"

#include "Common/ExceptionBoundary.h"
#include "CondensedFEM/CondensedSystem.h"
#include "CondensedFEM/DeformationCheck.h"
#include "CondensedFEM/PrecomputeStages.h"
#include "CondensedFEM/RefinedSolve.h"
#include "Mesh/MeshValidation.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace faceplan {

const char* MethodName(SolveMethod method) {
  switch (method) {
  case SolveMethod::Auto:
    return "Auto";
  case SolveMethod::DenseResponse:
    return "DenseResponse";
  case SolveMethod::CachedFactor:
    return "CachedFactor";
  case SolveMethod::RigidSegments:
    return "RigidSegments";
  case SolveMethod::FullReference:
    return "FullReference";
  case SolveMethod::LargeDeformationNewton:
    return "LargeDeformationNewton";
  case SolveMethod::LargeDeformationPrecomputed:
    return "LargeDeformationPrecomputed";
  }
  return "?";
}

const char* ElementOrderName(ElementOrder order) {
  switch (order) {
  case ElementOrder::Linear:
    return "Linear";
  case ElementOrder::Quadratic:
    return "Quadratic";
  case ElementOrder::QuadraticNodalPressure:
    return "QuadraticNodalPressure";
  }
  return "?";
}

namespace {

Status PrecomputeImpl(const PrecomputeRequest& request, std::shared_ptr<const CondensedSystem>& out,
                      const std::atomic<bool>* cancel, const ProgressCallback& progress) {
  StageClock total;
  PrecomputeState state(request, cancel, progress);
  for (Status (*stage)(PrecomputeState&) :
       {ValidatePrecomputeRequest, SeparateNodes, AssembleStiffness, SeparateBlocks,
        ReorderFreeDofs, FinishMeshChecks}) {
    Status s = stage(state);
    if (!s) {
      // The mesh checks ran beside these stages: a piece not held is the cause to report.
      if (state.meshChecks.valid())
        if (MeshChecks checks = state.meshChecks.get(); !checks.status)
          return checks.status;
      return s;
    }
  }
  if (Status s = ChooseSolveMethod(state); !s)
    return s;
  for (Status (*stage)(PrecomputeState&) : {Factorize, Condense}) {
    Status s = stage(state);
    if (!s)
      return s;
  }
  SystemInfo& info = state.sys->info;
  info.precomputeTimings[Stage::Total].ms = total.elapsedMs();
  info.warnings = state.status.warnings;
  state.report(1.0, "done");
  out = state.sys;
  return state.status;
}

} // namespace

Status Precompute(const PrecomputeRequest& request, std::shared_ptr<const CondensedSystem>& system,
                  const std::atomic<bool>* cancel, const ProgressCallback& progress) {
  system.reset();
  return ReturnStatusOnException("the precompute", [&]() -> Status {
    return PrecomputeImpl(request, system, cancel, progress);
  });
}

namespace {

// The per-edit solve in stages, as PrecomputeImpl runs the precompute's: each stage reads the
// system and the input, hands its results on in SolveState and returns an error or Ok; warnings
// accumulate in SolveState::status.
struct SolveState {
  SolveState(const CondensedSystem& s, const SolveInput& i, SolveResult& r)
      : sys(s), input(i), result(r) {}
  const CondensedSystem& sys;
  const SolveInput& input;
  SolveResult& result;
  Status status = Status::Ok(); // carries the warnings
  StageClock clock;             // lapped by the timed stages

  Eigen::VectorXd roi;       // the ROI DOFs' prescribed values
  bool rigidProduct = false; // the response to the segment parameters gives the kept DOFs
  Eigen::VectorXd load;      // loads on the free DOFs (empty when none is given)
  bool loadGiven = false, hasLoad = false;
  Eigen::VectorXd parameters; // the segment parameters (rigidProduct)
  Eigen::VectorXd keptFree;   // the kept free DOFs' displacements
  Eigen::VectorXd freeValues; // every free DOF's displacement (full solves only)
};

// The result's fields that come from the precompute.
void StartResult(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  SolveResult& result = state.result;
  result = SolveResult();
  result.method = sys.method;
  result.backend = sys.backendName;
  for (int s = 0; s < kNumStages; ++s) {
    result.timings.stages[s] = sys.info.precomputeTimings.stages[s];
    result.timings.stages[s].reused = true;
  }
  result.conditionEstimate = sys.info.conditionEstimate;
  result.elementOrder = sys.info.elementOrder;
  result.redoneInDouble = sys.responseRedoneInDouble;
  result.precisionNote = sys.precisionNote;
}

// Boundary condition: the ROI DOFs' prescribed values from the movable displacements (mid-edge
// ROI nodes of quadratic cells take the mean of their ends, sliding nodes their normal part).
Status ApplyBoundaryCondition(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  const SolveInput& input = state.input;
  const Eigen::Index movable = static_cast<Eigen::Index>(sys.movableNodes.size());
  if (input.movableDisplacement.rows() != movable)
    return Status::Error("expected " + std::to_string(movable) + " ROI displacements, got " +
                         std::to_string(input.movableDisplacement.rows()));
  if (!input.movableDisplacement.allFinite())
    return Status::Error("prescribed displacements contain NaN or infinite values");
  state.roi = sys.movableToRoi *
              Eigen::Map<const Eigen::VectorXd>(input.movableDisplacement.data(), 3 * movable);
  state.rigidProduct = sys.method == SolveMethod::RigidSegments && !input.recoverInterior;
  if (sys.method == SolveMethod::RigidSegments && input.segmentTransforms.empty())
    return Status::Error(
        "RigidSegments needs one transform per segment (SolveInput::segmentTransforms)");
  if (!input.segmentTransforms.empty() && sys.segments > 0) {
    Status check =
        CheckSegmentDisplacements(sys.cornerMesh.points, sys.segmentSets, input.segmentTransforms,
                                  input.movableDisplacement, sys.meshExtent);
    if (!check)
      return check;
  }
  state.result.timings[Stage::BoundaryCondition] = {state.clock.lapMs(), false};
  return Status::Ok();
}

// Loads on the free DOFs (none on most edits: then no vector is built).
Status ApplyLoads(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  const SolveInput& input = state.input;
  const NodeLayout& layout = sys.layout;
  const int freeDofs = 3 * layout.freeNodes();
  if (!input.gravity.allFinite())
    return Status::Error("gravity contains NaN values");
  state.loadGiven = input.nodalLoads.size() > 0 || input.gravity.squaredNorm() > 0.0;
  Eigen::VectorXd& load = state.load;
  load = Eigen::VectorXd::Zero(state.loadGiven ? freeDofs : 0);
  if (input.nodalLoads.size() > 0) {
    if (input.nodalLoads.rows() != sys.numOutputNodes)
      return Status::Error("nodal loads must have one row per mesh point");
    if (!input.nodalLoads.allFinite())
      return Status::Error("nodal loads contain NaN values");
    for (int pos = 0; pos < layout.freeNodes(); ++pos)
      if (layout.meshNode[pos] < sys.numOutputNodes) // mid-edge nodes of quadratic cells get none
        load.segment<3>(3 * pos) = input.nodalLoads.row(layout.meshNode[pos]).transpose();
  }
  if (input.gravity.squaredNorm() > 0.0)
    for (int pos = 0; pos < layout.freeNodes(); ++pos)
      load.segment<3>(3 * pos) += sys.nodeMass[pos] * input.gravity;
  // Sliding nodes: loads in their normal frame; the normal one is taken by the contact.
  for (int pos = 0; state.loadGiven && pos < layout.freeNodes(); ++pos)
    if (const int slide = sys.slidingOfPosition.empty() ? -1 : sys.slidingOfPosition[pos];
        slide >= 0) {
      const Eigen::Vector3d local = sys.slidingFrame[slide].transpose() * load.segment<3>(3 * pos);
      load.segment<3>(3 * pos) << 0.0, local[1], local[2];
    }
  state.hasLoad = state.loadGiven && load.squaredNorm() > 0.0;
  state.result.timings[Stage::Load] = {state.clock.lapMs(), false};
  return Status::Ok();
}

// DenseResponse and RigidSegments: the kept DOFs from the precomputed response (to the ROI DOFs
// or to the segment parameters), plus a load's response with the cached factor.
Status ApplyResponse(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  SolveResult& result = state.result;
  if (state.rigidProduct)
    state.parameters = SegmentParameters(sys.segmentSets, state.input.segmentTransforms,
                                         state.input.movableDisplacement);
  const Status applied = sys.responseOperator->apply(
      state.rigidProduct ? state.parameters : state.roi, state.keptFree);
  if (!applied)
    return Status::Error("dense response update failed: " + applied.message);
  result.relativeResidual = sys.responseResidual;
  result.residualFromPrecompute = true;
  if (state.hasLoad) {
    Eigen::VectorXd loadResponse;
    double residual = 0.0;
    Status s = CachedLoadResponse(sys, state.load, loadResponse, residual, result.refinementSteps);
    if (!s)
      return s;
    result.relativeResidual = std::max(result.relativeResidual, residual);
    state.keptFree += loadResponse.head(state.keptFree.size());
  }
  return Status::Ok();
}

// CachedFactor, FullReference and any solve that recovers the interior: every free DOF with the
// cached factor, refined.
Status SolveWithFactor(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  SolveResult& result = state.result;
  const Eigen::VectorXd& roi = state.roi;
  const int freeDofs = 3 * sys.layout.freeNodes();
  Eigen::VectorXd rhs = state.loadGiven ? state.load : Eigen::VectorXd::Zero(freeDofs);
  Eigen::VectorXd roiLoad; // -K_FR roi: non-zero only on the ROI-coupled (trailing) DOFs
  if (roi.size() > 0) {
    roiLoad.noalias() = -(sys.kfr * roi);
    rhs += roiLoad;
  }
  // With the ROI-coupled DOFs ordered last, the ROI part needs only a backward substitution;
  // a load's part is solved in full and reused while the load does not change.
  Eigen::MatrixXd initial;
  if (roi.size() > 0 && sys.factor.trailingDofs() > 0) {
    const SparseMatrix roiRhs = roiLoad.sparseView();
    Status s = sys.factor.solveTrailing(roiRhs, initial);
    if (!s)
      return s;
    if (state.hasLoad) {
      Eigen::VectorXd loadResponse;
      double loadResidual = 0.0;
      int loadSteps = 0; // the refinement of the whole solution below is what this solve reports
      s = CachedLoadResponse(sys, state.load, loadResponse, loadResidual, loadSteps);
      if (!s)
        return s;
      initial.col(0) += loadResponse;
    }
  }
  Eigen::MatrixXd x;
  Status s = RefinedSolve(sys, rhs, x, false, sys.residualTolerance, sys.maxRefinementSteps,
                          result.relativeResidual, result.refinementSteps, nullptr,
                          initial.size() > 0 ? &initial : nullptr);
  if (!s)
    return s;
  state.freeValues = x.col(0);
  state.keptFree = state.freeValues.head(3 * sys.layout.keptFree);
  return Status::Ok();
}

// The free DOFs by the system's method: the precomputed response or a solve with the factor.
Status SolveFreeDofs(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  const bool fullSolve = !(sys.method == SolveMethod::DenseResponse || state.rigidProduct) ||
                         state.input.recoverInterior;
  Status s = Status::Ok();
  if (sys.layout.freeNodes() == 0)
    state.freeValues.resize(0);
  else if (!fullSolve)
    s = ApplyResponse(state);
  else
    s = SolveWithFactor(state);
  if (!s)
    return s;
  state.result.timings[Stage::Solve] = {state.clock.lapMs(), false};
  return Status::Ok();
}

// Outputs in the caller's numbering; non-finite values are an error, a missed tolerance a warning.
Status MapOutputs(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  SolveResult& result = state.result;
  const Eigen::Index keptCount = static_cast<Eigen::Index>(sys.kept.size());
  if (sys.keptIsFreeBlock && state.keptFree.size() >= 3 * keptCount) {
    result.keptDisplacement = Eigen::Map<const RowVectors3d>(state.keptFree.data(), keptCount, 3);
  } else {
    result.keptDisplacement.resize(keptCount, 3);
    for (Eigen::Index k = 0; k < keptCount; ++k)
      result.keptDisplacement.row(k) =
          NodeDisplacement(sys, sys.kept[k], state.roi, state.keptFree);
  }
  if (state.input.recoverInterior) {
    result.allDisplacement.resize(sys.numOutputNodes, 3);
    for (Eigen::Index i = 0; i < sys.numOutputNodes; ++i)
      result.allDisplacement.row(i) =
          NodeDisplacement(sys, static_cast<int>(i), state.roi, state.freeValues);
  }
  if (!result.keptDisplacement.allFinite() || !result.allDisplacement.allFinite() ||
      !std::isfinite(result.relativeResidual))
    return Status::Error("the solve produced non-finite values (ill-conditioned system?)");
  if (result.relativeResidual > 1e3 * sys.residualTolerance) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "relative residual " << result.relativeResidual << " after " << result.refinementSteps
        << " refinement steps misses the tolerance " << sys.residualTolerance
        << " (condition estimate " << result.conditionEstimate << ")";
    state.status.warnings.push_back(msg.str());
  }
  return Status::Ok();
}

// Large-strain and inversion check on the caller's linear cells: every cell when the interior
// was recovered, else the cells whose corners are all kept or constrained.
void CheckStrain(SolveState& state) {
  const CondensedSystem& sys = state.sys;
  const SolveInput& input = state.input;
  SolveResult& result = state.result;
  std::vector<std::string>& warnings = state.status.warnings;
  if (sys.strainWarningLimit <= 0.0)
    return;
  DeformationReport deformation;
  if (input.recoverInterior) {
    deformation =
        CheckDeformation(sys.cornerMesh, result.allDisplacement, warnings, sys.strainWarningLimit);
  } else if (!sys.checkableCells.empty()) {
    if (state.rigidProduct && !state.hasLoad && !sys.boundedCells.empty()) {
      // Linear in the segment parameters: cells ordered by their strain bound
      // (DeformationCheck.h).
      deformation = CheckBoundedCells(sys, state.parameters, input.segmentTransforms,
                                      input.movableDisplacement, result.keptDisplacement, warnings);
    } else {
      RowVectors3d known = RowVectors3d::Zero(sys.numOutputNodes, 3);
      for (Eigen::Index k = 0; k < input.movableDisplacement.rows(); ++k)
        known.row(sys.movableNodes[k]) = input.movableDisplacement.row(k);
      for (size_t k = 0; k < sys.kept.size(); ++k)
        known.row(sys.kept[k]) = result.keptDisplacement.row(k);
      deformation = CheckDeformation(sys.cornerMesh, known, warnings, sys.strainWarningLimit,
                                     &sys.checkableCells);
    }
  }
  result.largestStrain = deformation.largestStrain;
  result.invertedCells = static_cast<long long>(deformation.invertedCells.size());
}

Status SolveImpl(const CondensedSystem& sys, const SolveInput& input, SolveResult& result) {
  StageClock total;
  SolveState state(sys, input, result);
  StartResult(state);
  for (Status (*stage)(SolveState&) :
       {ApplyBoundaryCondition, ApplyLoads, SolveFreeDofs, MapOutputs}) {
    Status s = stage(state);
    if (!s)
      return s;
  }
  CheckStrain(state);
  result.warnings = state.status.warnings;
  result.timings[Stage::Total] = {total.elapsedMs(), false};
  return state.status;
}

} // namespace

Status Solve(const CondensedSystem& system, const SolveInput& input, SolveResult& result) {
  return ReturnStatusOnException("the solve",
                                 [&]() -> Status { return SolveImpl(system, input, result); });
}

SystemInfo Describe(const CondensedSystem& system) {
  return system.info;
}

} // namespace faceplan
