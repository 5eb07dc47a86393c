// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformConvert.h"

#include "CondensedFEM/PhysicalUnits.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkDataSetSurfaceFilter.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

namespace faceplan {
namespace fem_filter {

void ToTetMesh(vtkUnstructuredGrid* tissue, TetMesh& mesh) {
  const vtkIdType n = tissue->GetNumberOfPoints(), m = tissue->GetNumberOfCells();
  mesh.points.resize(n, 3);
  for (vtkIdType i = 0; i < n; ++i)
    tissue->GetPoint(i, &mesh.points(i, 0));
  mesh.tets.resize(m, 4);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < m; ++c) {
    tissue->GetCellPoints(c, ids);
    for (int k = 0; k < 4; ++k)
      mesh.tets(c, k) = static_cast<int>(ids->GetId(k));
  }
}

Status ToMaterials(vtkUnstructuredGrid* tissue, const Settings& settings, Materials& materials) {
  Materials si =
      Materials::Uniform(settings.youngsModulus, settings.poissonRatio, settings.density);
  const vtkIdType m = tissue->GetNumberOfCells();
  auto perCell = [&](const char* name, Eigen::VectorXd& values) {
    vtkDataArray* array =
        settings.useCellMaterials ? tissue->GetCellData()->GetArray(name) : nullptr;
    if (!array)
      return;
    values.resize(m);
    for (vtkIdType c = 0; c < m; ++c)
      values[c] = array->GetComponent(c, 0);
  };
  perCell("YoungsModulus", si.youngsModulus);
  perCell("PoissonRatio", si.poissonRatio);
  return MaterialsInMeshUnits(si, settings.lengthUnit, materials);
}

TissueBoundary ExtractBoundary(vtkUnstructuredGrid* tissue) {
  vtkNew<vtkDataSetSurfaceFilter> surface;
  surface->SetInputData(tissue);
  surface->PassThroughPointIdsOn();
  surface->Update();
  TissueBoundary boundary;
  boundary.surface = surface->GetOutput();
  vtkIdTypeArray* original = vtkIdTypeArray::SafeDownCast(
      boundary.surface->GetPointData()->GetArray(surface->GetOriginalPointIdsName()));
  for (vtkIdType k = 0; original && k < original->GetNumberOfTuples(); ++k)
    boundary.nodes.push_back(original->GetValue(k));
  vtkPolyData* s = boundary.surface;
  boundary.cellTypes = vtkSmartPointer<vtkUnsignedCharArray>::New();
  boundary.cellTypes->SetNumberOfValues(s->GetNumberOfCells());
  boundary.cells = vtkSmartPointer<vtkCellArray>::New();
  boundary.cells->AllocateExact(s->GetNumberOfCells(), 3 * s->GetNumberOfCells());
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < s->GetNumberOfCells(); ++c) {
    boundary.cellTypes->SetValue(c, static_cast<unsigned char>(s->GetCellType(c)));
    s->GetCellPoints(c, ids);
    boundary.cells->InsertNextCell(ids);
  }
  return boundary;
}

} // namespace fem_filter
} // namespace faceplan
