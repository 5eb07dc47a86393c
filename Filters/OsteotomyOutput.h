// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Osteotomy's outputs built from Core's result (private to FacePlan::Filters).
#include "Osteotomy/CutPlanes.h"
#include "Osteotomy/Osteotomy.h"

#include <array>
#include <vector>

class vtkCellArray;
class vtkFieldData;
class vtkPolyData;

namespace faceplan {
namespace osteotomy_filter {

// Port 0: the moved points, the split bone's triangles, point arrays Displacement, ROIMask (uint8)
// and SegmentId (int), the split's carried point arrays (the input's one-component arrays,
// interpolated at the points the cut added), the input's field data with SegmentTransform and
// SegmentNote replaced.
void BuildBoneOutput(const OsteotomyResult& result, vtkPolyData* split, vtkFieldData* inputField,
                     vtkPolyData* output);

// Port 1: each plane's section of the box as one polygon, cell array CutPlane = 1, 2.
void BuildCutPlaneOutput(const std::vector<CutPlane>& planes, const std::array<double, 6>& box,
                         vtkPolyData* output);

} // namespace osteotomy_filter
} // namespace faceplan
