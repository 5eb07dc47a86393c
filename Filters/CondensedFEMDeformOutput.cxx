// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformOutput.h"
#include "FacePlanFieldData.h"

#include "vtkCellArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdList.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"
#include "vtkTable.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

namespace faceplan {
namespace fem_filter {

using fielddata::AddScalar;
using fielddata::AddString;

void BuildDeformedTissue(vtkUnstructuredGrid* tissue, const TissueBoundary& boundary,
                         const RowVectors3d& restPoints, const SolveOutcome& outcome,
                         OutputMode mode, vtkUnstructuredGrid* output) {
  // The structure (cells, passed arrays) is shared with the tissue or with the cached boundary, so
  // an update writes only the new points and Displacement.
  const SolveResult& result = outcome.result;
  const bool volume = mode == OutputMode::Volume;
  const vtkIdType n = volume ? tissue->GetNumberOfPoints() : boundary.surface->GetNumberOfPoints();
  const RowVectors3d& u = volume ? result.allDisplacement : result.keptDisplacement;
  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  displacement->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(n);
  double* d = displacement->GetPointer(0);
  double* x = coordinates->GetPointer(0);
  for (vtkIdType i = 0; i < n; ++i) {
    // Surface: kept == boundary nodes, in the surface's point order.
    const Eigen::Index rest = volume ? i : static_cast<Eigen::Index>(boundary.nodes[i]);
    for (int c = 0; c < 3; ++c) {
      d[3 * i + c] = u(i, c);
      x[3 * i + c] = restPoints(rest, c) + u(i, c);
    }
  }
  vtkNew<vtkPoints> moved;
  moved->SetData(coordinates);
  if (volume) {
    output->ShallowCopy(tissue);
  } else {
    output->Initialize();
    output->SetCells(boundary.cellTypes, boundary.cells);
    output->GetPointData()->ShallowCopy(boundary.surface->GetPointData());
  }
  output->SetPoints(moved);
  output->GetPointData()->AddArray(displacement);
  output->GetPointData()->SetActiveVectors("Displacement");
  // Active scalars too: ParaView colours a new display by them (by magnitude, in mm).
  output->GetPointData()->SetActiveScalars("Displacement");
}

void AddFieldData(const SolveOutcome& outcome, const Settings& settings,
                  vtkUnstructuredGrid* output) {
  const SolveResult& result = outcome.result;
  vtkNew<vtkFieldData> fd;
  AddScalar(fd, "RelativeResidual", result.relativeResidual);
  AddScalar(fd, "ResidualFromPrecompute", result.residualFromPrecompute ? 1.0 : 0.0);
  AddScalar(fd, "SolveTimeMs", result.timings[Stage::Total].ms);
  AddScalar(fd, "PrecomputeTimeMs", outcome.precomputeMs);
  AddScalar(fd, "PrecomputeReused",
            outcome.freshPrecompute || settings.fullReference() || outcome.newton ? 0.0 : 1.0);
  AddString(fd, "Method", MethodName(result.method));
  AddString(fd, "Model", outcome.model);
  AddString(fd, "ModelNote", outcome.modelNote);
  if (outcome.largeDeformation) {
    AddString(fd, "LargeDeformationSolver", outcome.newton ? "Newton" : "Precomputed");
    if (!outcome.solverNote.empty())
      AddString(fd, "SolverNote", outcome.solverNote);
    AddScalar(fd, "Converged", outcome.precomputedReport.stoppedAtLimit ? 0.0 : 1.0);
    double smallest = 0.0;
    int lifted = 0;
    if (outcome.newton) {
      const LargeDeformationReport& report = outcome.largeDeformationReport;
      AddScalar(fd, "LoadSteps", report.loadSteps);
      AddScalar(fd, "NewtonIterations", report.newtonIterations);
      smallest = report.smallestVolumeRatio;
      lifted = report.liftedNodes;
    } else {
      const PrecomputedLargeDeformationReport& report = outcome.precomputedReport;
      AddScalar(fd, "QuasiNewtonIterations", report.iterations);
      AddScalar(fd, "ForceEvaluations", report.evaluations);
      AddScalar(fd, "FactorSolves", report.factorSolves);
      AddScalar(fd, "Refactorizations", report.refactorizations);
      AddScalar(fd, "PartialRefactorizations", report.partialRefactorizations);
      AddScalar(fd, "WarmStarted", report.warmStarted ? 1.0 : 0.0);
      smallest = report.smallestVolumeRatio;
      lifted = report.liftedNodes;
    }
    AddScalar(fd, "SmallestVolumeRatio", smallest);
    // The iterates' time (ms since the solve started) and relative residual, for plots.
    const auto& history = outcome.newton ? outcome.largeDeformationReport.convergence
                                         : outcome.precomputedReport.convergence;
    vtkNew<vtkDoubleArray> convergence;
    convergence->SetName("ConvergenceHistory");
    convergence->SetNumberOfComponents(2);
    for (const auto& [ms, residual] : history)
      convergence->InsertNextTuple2(ms, residual);
    fd->AddArray(convergence);
    if (settings.liftOff)
      AddScalar(fd, "LiftedNodes", lifted);
  }
  AddString(fd, "Backend", result.backend);
  if (settings.verify)
    AddScalar(fd, "VerifyMaxRelativeError", outcome.verifyError);
  AddScalar(fd, "ConditionEstimate", result.conditionEstimate);
  AddScalar(fd, "LargestStrain", result.largestStrain);
  AddScalar(fd, "InvertedCells", static_cast<double>(result.invertedCells));
  AddString(fd, "ElementOrder", ElementOrderName(result.elementOrder));
  output->SetFieldData(fd);
}

void BuildStageTable(const SolveOutcome& outcome, vtkTable* table) {
  const SolveResult& result = outcome.result;
  vtkNew<vtkStringArray> stage, backend;
  stage->SetName("Stage");
  backend->SetName("Backend");
  vtkNew<vtkDoubleArray> timeMs, cachedMs;
  timeMs->SetName("TimeMs");
  cachedMs->SetName("CachedTimeMs");
  vtkNew<vtkIntArray> reused;
  reused->SetName("Reused");
  // TimeMs is this update's: a reused stage took no time now. CachedTimeMs keeps what the reused
  // result took when it was computed, so an old figure never reads as the current one.
  auto addRow = [&](const char* name, double ms, bool wasReused) {
    stage->InsertNextValue(name);
    timeMs->InsertNextValue(wasReused ? 0.0 : ms);
    cachedMs->InsertNextValue(wasReused ? ms : 0.0);
    reused->InsertNextValue(wasReused ? 1 : 0);
    backend->InsertNextValue(result.backend);
  };
  // Total is this update's time: the solve, plus the precompute when this update ran it.
  // PrecomputeTotal is the (cached or fresh) precompute's own total.
  double thisUpdateMs = result.timings[Stage::Total].ms;
  if (outcome.freshPrecompute)
    thisUpdateMs += outcome.precomputeMs;
  for (int k = 0; k < kNumStages; ++k) {
    const Stage s = static_cast<Stage>(k);
    if (s == Stage::Total)
      addRow(StageName(s), thisUpdateMs, false);
    else
      addRow(StageName(s), result.timings.stages[k].ms, result.timings.stages[k].reused);
  }
  addRow("PrecomputeTotal", outcome.precomputeMs,
         !outcome.freshPrecompute && outcome.precomputeMs > 0.0);
  table->AddColumn(stage);
  table->AddColumn(timeMs);
  table->AddColumn(reused);
  table->AddColumn(backend);
  table->AddColumn(cachedMs);
}

} // namespace fem_filter
} // namespace faceplan
