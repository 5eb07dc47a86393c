// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Geometry of one tetrahedron, shared by mesh validation and the element stiffness.
#include <Eigen/Core>

namespace faceplan {

using TetCorners = Eigen::Matrix<double, 4, 3>; // one corner per row

// Signed volume det[x1-x0, x2-x0, x3-x0] / 6.
double TetVolume(const TetCorners& corners);

} // namespace faceplan
