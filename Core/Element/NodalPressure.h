// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Nodal-averaged pressure (locking-free volumetric term) for quadratic (10-node) tetrahedra.
//
// The strain energy is split into a shear part mu eps:eps, integrated per cell as usual, and a
// volumetric part lambda/2 (div u)^2 that is replaced by a continuous, piecewise-linear pressure on
// the corner nodes with a lumped (row-sum) pressure mass, eliminated exactly:
//
//   p = sum_n p_n phi_n,   g_n(u) = int phi_n div u,   M_n = int phi_n / lambda,
//   p_n = g_n(u) / M_n,    K_vol = G^T diag(1 / M_n) G.
//
// phi_n is the linear hat function of corner node n: the Taylor-Hood P2-P1 element with a lumped
// pressure mass, its pressure eliminated exactly. It is symmetric and positive definite, needs no
// extra unknowns and only changes the assembled stiffness; the price is a wider stencil: K_vol
// couples every pair of nodes that share a corner node's patch (about 6x the Cholesky factor of
// the mean-dilatation TET10 on a 35k-cell shell). (The same idea on 4-node cells, the averaged
// nodal pressure tetrahedron of Bonet & Burton 1998, still locked on that shell:
// docs/STABILITY.md.) Per-cell lambda enters through M_n (the harmonic, volume-weighted mean over
// the patch); cells with lambda <= 0 (nu <= 0) keep their own volumetric term and take no part in
// the nodal pressure.
#include "Element/StiffnessAssembly.h"
#include "Mesh/TetMesh.h"

#include <vector>

namespace faceplan {

// Materials whose cells give the shear part only: E' = E / (1 + nu) = 2 mu and nu' = 0 (so
// lambda' = 0) where lambda > 0; other cells unchanged. Per-cell arrays if either input is.
Materials ShearOnlyMaterials(const Materials& materials);

// Upper triangle of K_vol in the assembly numbering of BuildAssemblyPattern /
// BuildCellAssemblyPattern (DOF 3 dofNode[i] + c of mesh node i; nodes with dofNode < 0 carry no
// DOFs and are dropped), size 3 numDofNodes. `cells` holds numCells x nodesPerCell ids row by row
// (nodesPerCell must be 10, VTK order, corners first); `points` the solver mesh's points. Pressure
// nodes are the cells' corner nodes. Fails on a cell with a non-positive Jacobian.
Status NodalPressureStiffness(const RowVectors3d& points, const int* cells, Eigen::Index numCells,
                              int nodesPerCell, const Materials& materials,
                              const std::vector<int>& dofNode, int numDofNodes,
                              SparseMatrix& upper);

// Adds K_vol to an assembled upper triangle (same numbering) in place.
Status AddNodalPressureStiffness(SparseMatrix& upper, const RowVectors3d& points, const int* cells,
                                 Eigen::Index numCells, int nodesPerCell,
                                 const Materials& materials, const std::vector<int>& dofNode,
                                 int numDofNodes);

} // namespace faceplan
