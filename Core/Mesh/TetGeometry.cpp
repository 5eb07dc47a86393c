// SPDX-License-Identifier: BSD-3-Clause
#include "Mesh/TetGeometry.h"

#include <Eigen/LU>

namespace faceplan {

double TetVolume(const TetCorners& c) {
  Eigen::Matrix3d edges;
  edges.col(0) = (c.row(1) - c.row(0)).transpose();
  edges.col(1) = (c.row(2) - c.row(0)).transpose();
  edges.col(2) = (c.row(3) - c.row(0)).transpose();
  return edges.determinant() / 6.0;
}

} // namespace faceplan
