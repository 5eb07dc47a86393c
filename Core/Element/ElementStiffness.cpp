// SPDX-License-Identifier: BSD-3-Clause
#include "Element/ElementStiffness.h"

#include "Common/ParallelFor.h"

#include <Eigen/Dense>

namespace faceplan {

void LameParameters(double E, double nu, double& lambda, double& mu) {
  lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  mu = E / (2.0 * (1.0 + nu));
}

ElementMatrix TetStiffness(const TetCorners& c, double E, double nu) {
  Eigen::Matrix3d edges;
  edges.col(0) = (c.row(1) - c.row(0)).transpose();
  edges.col(1) = (c.row(2) - c.row(0)).transpose();
  edges.col(2) = (c.row(3) - c.row(0)).transpose();
  const double volume = edges.determinant() / 6.0;
  // Rows of edges^-1 are the gradients of the shape functions of corners 1..3.
  const Eigen::Matrix3d inv = edges.inverse();
  Eigen::Matrix<double, 4, 3> grad;
  grad.row(1) = inv.row(0);
  grad.row(2) = inv.row(1);
  grad.row(3) = inv.row(2);
  grad.row(0) = -(grad.row(1) + grad.row(2) + grad.row(3));

  double lambda, mu;
  LameParameters(E, nu, lambda, mu);
  // Block (a,b) of B^T D B V: V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I).
  ElementMatrix ke;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      const Eigen::RowVector3d ga = grad.row(a), gb = grad.row(b);
      Eigen::Matrix3d block = lambda * ga.transpose() * gb + mu * gb.transpose() * ga;
      block.diagonal().array() += mu * ga.dot(gb);
      ke.block<3, 3>(3 * a, 3 * b) = volume * block;
    }
  }
  return ke;
}

void ComputePackedElementStiffness(const TetMesh& mesh, const Materials& materials,
                                   PackedElementMatrices& packed) {
  const Eigen::Index m = mesh.numTets();
  packed.resize(static_cast<size_t>(m) * kPackedElementSize);
  ParallelFor(m, 20000, [&](std::int64_t begin, std::int64_t end) {
    TetCorners corners;
    for (std::int64_t e = begin; e < end; ++e) {
      for (int k = 0; k < 4; ++k)
        corners.row(k) = mesh.points.row(mesh.tets(e, k));
      const ElementMatrix ke = TetStiffness(corners, materials.E(e), materials.nu(e));
      double* out = packed.data() + static_cast<size_t>(e) * kPackedElementSize;
      for (int p = 0; p < 12; ++p)
        for (int q = p; q < 12; ++q)
          *out++ = ke(p, q);
    }
  });
}

} // namespace faceplan
