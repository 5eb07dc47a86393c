// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Rigid segments: movable nodes that follow one affine motion u(x) = A x + b per segment, with
// [A | b] = [R - I | t] for a segment moved by x -> R x + t. Their ROI values then lie in a
// 12-dimensional space per segment, which the RigidSegments solve method exploits.
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"
#include "Mesh/NodeSets.h"
#include "Mesh/TetMesh.h"

#include <vector>

namespace faceplan {

// Row-major 3x4 affine map [R | t]: x -> R x + t.
using SegmentTransform = Eigen::Matrix<double, 3, 4, Eigen::RowMajor>;

// Number of segments (the largest id in sets.movableSegment; 0 without segments).
int SegmentCount(const NodeSets& sets);

// Checks that every movable node of a segment k >= 1 is displaced by its transform,
// |u - ((R - I) x + t)| <= 1e-8 * (the segment's largest displacement, or the mesh extent's 1e-12
// when nothing moves), and that the transforms are finite and one per segment. The error names the
// segment, the node and the mismatch.
Status CheckSegmentDisplacements(const RowVectors3d& points, const NodeSets& sets,
                                 const std::vector<SegmentTransform>& transforms,
                                 const RowVectors3d& movableDisplacement,
                                 double meshExtent = -1.0); // < 0: computed from `points`

// B: the caller's movable displacements (3 per node, node-major) as a linear function of the
// parameters p = [12 per segment: row-major [R - I | t]; 3 per movable node of segment 0]. Nodes
// of segment k take u = (R - I) x + t; nodes of segment 0 take their own slot.
SparseMatrix SegmentBasis(const RowVectors3d& points, const NodeSets& sets);

// p for given transforms and displacements (the segment-0 nodes' rows of `movableDisplacement`).
Eigen::VectorXd SegmentParameters(const NodeSets& sets,
                                  const std::vector<SegmentTransform>& transforms,
                                  const RowVectors3d& movableDisplacement);

// The movable displacements with every segment node's row replaced by its segment's motion at the
// node, (R - I) x + t: a node tied to a rigidly moved segment moves with it as one body.
RowVectors3d FollowSegments(const RowVectors3d& points, const NodeSets& sets,
                            const std::vector<SegmentTransform>& transforms,
                            const RowVectors3d& movableDisplacement);

} // namespace faceplan
