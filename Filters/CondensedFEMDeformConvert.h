// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Step 2 of CondensedFEMDeform: the tissue as Core's mesh and materials, and its boundary surface
// (the nodes the solve reports). Private to FacePlan::Filters; inputs are validated before.
#include "CondensedFEMDeformSettings.h"

#include "Common/Status.h"
#include "Mesh/TetMesh.h"

#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <vector>

class vtkCellArray;
class vtkPolyData;
class vtkUnsignedCharArray;
class vtkUnstructuredGrid;

namespace faceplan {
namespace fem_filter {

void ToTetMesh(vtkUnstructuredGrid* tissue, TetMesh& mesh);

// Uniform materials from the properties, per-cell where the tissue has the cell arrays (and
// UseCellMaterials is on), converted into the mesh's length unit by Core.
Status ToMaterials(vtkUnstructuredGrid* tissue, const Settings& settings, Materials& materials);

// The tissue's boundary triangles, with the tissue point id of each surface point, and its cells as
// an unstructured grid's (types and cell array), built once and shared by every Surface output.
struct TissueBoundary {
  vtkSmartPointer<vtkPolyData> surface;
  std::vector<vtkIdType> nodes;
  vtkSmartPointer<vtkUnsignedCharArray> cellTypes;
  vtkSmartPointer<vtkCellArray> cells;
};
TissueBoundary ExtractBoundary(vtkUnstructuredGrid* tissue);

} // namespace fem_filter
} // namespace faceplan
