// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Geometry conversion for vtkOsteotomy (private to FacePlan::Filters): the bone clipped to each
// convex piece of the cut with vtkClipClosedSurface (which caps the cut), triangulated, appended.
#include "Osteotomy/CutPlanes.h"

#include <vtkSmartPointer.h>

#include <cstdint>
#include <vector>

class vtkPolyData;

namespace faceplan {
namespace osteotomy_filter {

// `bone`: triangles with double points and the point arrays to interpolate. Returns the pieces
// appended in order; moves[i] = 1 for the points of pieces with ConvexPiece::moves.
vtkSmartPointer<vtkPolyData> ClipIntoPieces(vtkPolyData* bone,
                                            const std::vector<ConvexPiece>& pieces,
                                            std::vector<std::uint8_t>& moves);

} // namespace osteotomy_filter
} // namespace faceplan
