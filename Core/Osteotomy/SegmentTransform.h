// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Rigid motions of osteotomy segments: the move a planner types (translation, rotation angles,
// pivot), composition with earlier moves, and the flat 12-per-segment packing that the filters
// exchange (row-major 3x4 [R | t], mapping an undeformed point x to R x + t).
#include "Common/Status.h"

#include <Eigen/Core>

#include <vector>

namespace faceplan {

using AffineMap = Eigen::Matrix<double, 3, 4>; // [A | b]: x -> A x + b

struct SegmentMove {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();     // length unit of the bone
  Eigen::Vector3d rotationDegrees = Eigen::Vector3d::Zero(); // about X, then Y, then Z
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();           // fixed point of the rotation
};

// x -> Rz Ry Rx (x - pivot) + pivot + translation. Fails on a non-finite value.
Status RigidMotion(const SegmentMove& move, AffineMap& motion);

// The map x -> outer(inner(x)).
AffineMap Compose(const AffineMap& outer, const AffineMap& inner);

Eigen::Vector3d Apply(const AffineMap& map, const Eigen::Vector3d& x);

// The map that marks a segment whose motion is not one rigid transform.
AffineMap NotRigid();
bool IsFinite(const AffineMap& map);

// 12 doubles per map, row by row.
std::vector<double> PackSegmentTransforms(const std::vector<AffineMap>& maps);
// Reads `count` maps; entries missing from `packed` become NotRigid().
std::vector<AffineMap> UnpackSegmentTransforms(const std::vector<double>& packed, int count);

} // namespace faceplan
