// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One 3-vector per row, row-major (n x 3): mesh points, displacements, normals. Row-major so that
// a row is one point's x, y, z contiguous in memory, as VTK and CHOLMOD-free code expect.
#include <Eigen/Core>

namespace faceplan {

using RowVectors3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

} // namespace faceplan
