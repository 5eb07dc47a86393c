#include "CondensedFEMDeformOutput.h"

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
#include "vtkUnstructuredGrid.h"

namespace faceplan {
namespace fem_filter {

namespace {

void AddScalar(vtkFieldData* fd, const char* name, double value) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  fd->AddArray(a);
}

void AddString(vtkFieldData* fd, const char* name, const std::string& value) {
  vtkNew<vtkStringArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  fd->AddArray(a);
}

} // namespace

void BuildDeformedTissue(vtkUnstructuredGrid* tissue, const TissueBoundary& boundary,
                         const Points& restPoints, const SolveOutcome& outcome, OutputMode mode,
                         vtkUnstructuredGrid* output) {
  const SolveResult& result = outcome.result;
  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  vtkNew<vtkPoints> moved;
  moved->SetDataTypeToDouble();
  if (mode == OutputMode::Volume) {
    const vtkIdType n = tissue->GetNumberOfPoints();
    output->ShallowCopy(tissue);
    displacement->SetNumberOfTuples(n);
    moved->SetNumberOfPoints(n);
    for (vtkIdType i = 0; i < n; ++i) {
      const Eigen::RowVector3d u = result.allDisplacement.row(i);
      displacement->SetTuple3(i, u(0), u(1), u(2));
      const Eigen::RowVector3d p = restPoints.row(i) + u;
      moved->SetPoint(i, p(0), p(1), p(2));
    }
  } else {
    vtkPolyData* surface = boundary.surface;
    const vtkIdType ns = surface->GetNumberOfPoints();
    displacement->SetNumberOfTuples(ns);
    moved->SetNumberOfPoints(ns);
    for (vtkIdType k = 0; k < ns; ++k) { // kept == boundary nodes, in the surface's point order
      const Eigen::RowVector3d u = result.keptDisplacement.row(k);
      displacement->SetTuple3(k, u(0), u(1), u(2));
      const Eigen::RowVector3d p = restPoints.row(boundary.nodes[k]) + u;
      moved->SetPoint(k, p(0), p(1), p(2));
    }
    output->Initialize();
    output->GetPointData()->ShallowCopy(surface->GetPointData());
    vtkNew<vtkIdList> ids;
    output->Allocate(surface->GetNumberOfCells());
    for (vtkIdType c = 0; c < surface->GetNumberOfCells(); ++c) {
      surface->GetCellPoints(c, ids);
      output->InsertNextCell(surface->GetCellType(c), ids);
    }
  }
  output->SetPoints(moved);
  output->GetPointData()->AddArray(displacement);
  output->GetPointData()->SetActiveVectors("Displacement");
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
            outcome.freshPrecompute || settings.fullReference() ? 0.0 : 1.0);
  AddString(fd, "Method", MethodName(result.method));
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
  vtkNew<vtkDoubleArray> timeMs;
  timeMs->SetName("TimeMs");
  vtkNew<vtkIntArray> reused;
  reused->SetName("Reused");
  for (int k = 0; k < kNumStages; ++k) {
    stage->InsertNextValue(StageName(static_cast<Stage>(k)));
    timeMs->InsertNextValue(result.timings.stages[k].ms);
    reused->InsertNextValue(result.timings.stages[k].reused ? 1 : 0);
    backend->InsertNextValue(result.backend);
  }
  table->AddColumn(stage);
  table->AddColumn(timeMs);
  table->AddColumn(reused);
  table->AddColumn(backend);
}

} // namespace fem_filter
} // namespace faceplan
