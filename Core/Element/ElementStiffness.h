// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Linear 4-node tetrahedron, isotropic linear elasticity: Ke = B^T D B V.
#include "Common/UninitializedVector.h"
#include "Mesh/TetGeometry.h"
#include "Mesh/TetMesh.h"

#include <Eigen/Core>
#include <vector>

namespace faceplan {

using ElementMatrix = Eigen::Matrix<double, 12, 12>;
// Lame parameters from Young's modulus and Poisson ratio.
void LameParameters(double E, double nu, double& lambda, double& mu);

// Dense 12x12 stiffness of one tetrahedron; DOF order (node0 x,y,z, node1 x,y,z, ...).
ElementMatrix TetStiffness(const TetCorners& corners, double E, double nu);

// Number of entries in the upper triangle of a 12x12 element matrix, stored row by row
// (p <= q), which is how packed element matrices are laid out for assembly.
constexpr int kPackedElementSize = 78;

// All element matrices, packed upper triangles (m x 78, row-major), computed in parallel.
// This is the step the CUDA backend also implements. Uninitialized storage: every entry is
// written by the parallel loop, which then also takes the buffer's page faults.
using PackedElementMatrices = UninitializedVector<double>;
void ComputePackedElementStiffness(const TetMesh& mesh, const Materials& materials,
                                   PackedElementMatrices& packed);

} // namespace faceplan
