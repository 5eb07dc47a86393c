// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Osteotomy's checks and conversions between VTK and Core/Osteotomy (private to
// FacePlan::Filters): the input's validation, the cut planes from ParaView's implicit functions,
// and the bone's bookkeeping arrays (Displacement, ROIMask, SegmentId) on both sides of the split.
#include "Common/Status.h"
#include "Osteotomy/CutPlanes.h"
#include "Osteotomy/Osteotomy.h"

#include <vtkSmartPointer.h>

#include <cstdint>
#include <string>
#include <vector>

class vtkDataArray;
class vtkDataSet;
class vtkFieldData;
class vtkImplicitFunction;
class vtkPolyData;

namespace faceplan {
namespace osteotomy_filter {

// A vtkPolyData with points and polygons or strips, and no lines or vertices.
Status ValidateInput(vtkDataSet* input);

// The planes of the implicit functions (vtkPlane or a subclass: ParaView's plane adds an offset),
// checked and with unit normals.
Status ToCutPlanes(const std::vector<vtkImplicitFunction*>& functions,
                   std::vector<CutPlane>& planes);

// The point arrays that Osteotomy writes itself (Displacement, ROIMask, SegmentId).
bool IsBookkeepingArray(const std::string& name);

// The input's point arrays that the output carries: named, one component, not bookkeeping. Vectors
// and normals are left behind, since the move would invalidate them.
bool IsCarriedArray(vtkDataArray* array);

// The input triangulated, with double points and the bookkeeping arrays as doubles (zero where the
// input has none), so that clipping interpolates them along cut edges. The input's carried arrays
// (a scene's Released and Sliding flags, say) come along and are interpolated the same way.
vtkSmartPointer<vtkPolyData> BookkeepingBone(vtkPolyData* input);

// Core's view of the split bone: its triangles, the interpolated bookkeeping arrays, the input's
// SegmentTransform / SegmentNote field data and which points belong to the new segment.
Status ToOsteotomyBone(vtkPolyData* split, const std::vector<std::uint8_t>& moves,
                       vtkFieldData* inputField, OsteotomyBone& bone);

} // namespace osteotomy_filter
} // namespace faceplan
