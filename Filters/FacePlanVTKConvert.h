// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Conversions between VTK data sets and FacePlanCore's plain arrays (private to FacePlan::Filters).
#include "Mesh/SurfaceMesh.h"

#include <string>

class vtkDataSet;
class vtkPointSet;

namespace faceplan {
namespace vtkconvert {

enum class CellPolicy {
  EdgesOfAnyCell, // polygons as polygons, every other cell by its edges (for the ROI)
  SurfaceOnly     // polygons/strips as polygons, lines and vertices skipped, 3-D cells an error
};

// Copies the points (as double) and cells. On failure returns false and sets `why`.
bool ToSurfaceMesh(vtkPointSet* input, CellPolicy policy, SurfaceMesh& out, std::string& why);

} // namespace vtkconvert
} // namespace faceplan
