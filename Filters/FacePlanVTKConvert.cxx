// SPDX-License-Identifier: BSD-3-Clause
#include "FacePlanVTKConvert.h"

#include <vtkCell.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkGenericCell.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>

#include <cmath>
#include <string>

namespace faceplan {
namespace vtkconvert {

bool ToSurfaceMesh(vtkPointSet* input, CellPolicy policy, SurfaceMesh& out, std::string& why) {
  out = SurfaceMesh{};
  const vtkIdType n = input->GetNumberOfPoints();
  out.points.resize(n, 3);
  vtkPoints* pts = input->GetPoints();
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    pts->GetPoint(i, p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      why = "point " + std::to_string(i) + " has a NaN or infinite coordinate (not finite)";
      return false;
    }
    out.points.row(i) << p[0], p[1], p[2];
  }
  out.offsets.push_back(0);
  vtkNew<vtkIdList> ids;
  vtkNew<vtkGenericCell> cell;
  auto add = [&](std::initializer_list<std::int64_t> l) { out.addCell(l); };
  const vtkIdType numCells = input->GetNumberOfCells();
  for (vtkIdType c = 0; c < numCells; ++c) {
    const int type = input->GetCellType(c);
    input->GetCellPoints(c, ids);
    const vtkIdType m = ids->GetNumberOfIds();
    // Before any cell is built from them: VTK reads point coordinates by these ids unchecked.
    for (vtkIdType k = 0; k < m; ++k)
      if (ids->GetId(k) < 0 || ids->GetId(k) >= n) {
        why = "cell " + std::to_string(c) + " uses point id " + std::to_string(ids->GetId(k)) +
              ", out of range [0, " + std::to_string(n) + ")";
        return false;
      }
    switch (type) {
    case VTK_EMPTY_CELL:
    case VTK_VERTEX:
    case VTK_POLY_VERTEX:
      break;
    case VTK_TRIANGLE:
    case VTK_QUAD:
    case VTK_POLYGON:
      for (vtkIdType k = 0; k < m; ++k)
        out.connectivity.push_back(ids->GetId(k));
      out.offsets.push_back(std::int64_t(out.connectivity.size()));
      break;
    case VTK_PIXEL:
      add({ids->GetId(0), ids->GetId(1), ids->GetId(3), ids->GetId(2)});
      break;
    case VTK_TRIANGLE_STRIP:
      for (vtkIdType k = 0; k + 2 < m; ++k) {
        if (k % 2 == 0)
          add({ids->GetId(k), ids->GetId(k + 1), ids->GetId(k + 2)});
        else
          add({ids->GetId(k + 1), ids->GetId(k), ids->GetId(k + 2)});
      }
      break;
    case VTK_LINE:
    case VTK_POLY_LINE:
      if (policy == CellPolicy::EdgesOfAnyCell)
        for (vtkIdType k = 0; k + 1 < m; ++k)
          add({ids->GetId(k), ids->GetId(k + 1)});
      break;
    default:
      if (policy == CellPolicy::SurfaceOnly) {
        why = "cell " + std::to_string(c) + " is not a surface cell (VTK cell type " +
              std::to_string(type) + "); extract the surface first (Extract Surface)";
        return false;
      }
      input->GetCell(c, cell);
      for (int e = 0; e < cell->GetNumberOfEdges(); ++e) {
        vtkIdList* ep = cell->GetEdge(e)->GetPointIds();
        if (ep->GetNumberOfIds() >= 2)
          add({ep->GetId(0), ep->GetId(1)}); // corner points (higher-order edges list them first)
      }
      break;
    }
  }
  return true;
}

} // namespace vtkconvert
} // namespace faceplan
