// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The cut of an osteotomy: one or more planes. The segment is the part of the bone on the positive
// side of every plane (n . (x - o) > 0), or the rest when the sides are flipped.
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace faceplan {

struct CutPlane {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
};

// Checks that every plane is finite with a non-zero normal and makes the normals unit length.
Status NormalizeCutPlanes(std::vector<CutPlane>& planes);

bool OnSegmentSide(const std::vector<CutPlane>& planes, bool insideOut, const Eigen::Vector3d& x);

// 1 for points on the segment side. Fails when either side holds no point: such a cut moves
// nothing or everything.
Status ClassifyCutSides(const RowVectors3d& points, const std::vector<CutPlane>& planes,
                        bool insideOut, std::vector<std::uint8_t>& onSegmentSide);

// A convex piece of one side: the intersection of the half-spaces n . (x - o) >= 0 of `bounds`.
struct ConvexPiece {
  std::vector<CutPlane> bounds;
  bool moves = false;
};

// Convex pieces whose union is the bone: the positive side of every plane, and, for the rest,
// piece i = positive side of planes 0..i-1 and negative side of plane i (disjoint pieces, so
// clipping each one and capping it gives closed pieces that do not overlap).
std::vector<ConvexPiece> ConvexPiecesOfCut(const std::vector<CutPlane>& planes, bool insideOut);

// The polygon where a plane crosses an axis-aligned box (xmin, xmax, ymin, ymax, zmin, zmax),
// its corners in order around the plane's normal; empty when the plane misses the box.
std::vector<Eigen::Vector3d> PlaneBoxSection(const CutPlane& plane,
                                             const std::array<double, 6>& box);

} // namespace faceplan
