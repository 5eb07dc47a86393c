// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Quadratic 10-node tetrahedra (TET10), the locking-resistant element option of the condensed FEM.
// Core builds the TET10 mesh from the caller's linear mesh (one mid-edge node per edge, numbered
// after the corner nodes, so corner ids are unchanged), optionally snapping the mid-edge nodes of
// boundary edges onto a curved surface with a caller-supplied projection.
//
// Node order in a cell (VTK's): corners 0..3, then mid-edge nodes of edges
// (0,1), (1,2), (0,2), (0,3), (1,3), (2,3).
#include "Common/Status.h"
#include "Element/ElementStiffness.h"
#include "Element/StiffnessAssembly.h"
#include "Mesh/TetMesh.h"

#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

namespace faceplan {

// Corner pairs of the six mid-edge nodes, in VTK_QUADRATIC_TETRA order.
constexpr int kTet10EdgeCorners[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};

// Gradients of the 10 TET10 shape functions w.r.t. (L1, L2, L3) at barycentric point L.
Eigen::Matrix<double, 10, 3> Tet10ReferenceGradients(const Eigen::Vector4d& L);

// Places the mid-edge node of the boundary edge (a, b) whose straight midpoint is `midpoint`;
// return `midpoint` to keep it straight.
using MidEdgeProjection =
    std::function<Eigen::Vector3d(const Eigen::Vector3d& midpoint, int a, int b)>;

using Tet10Cells = Eigen::Matrix<int, Eigen::Dynamic, 10, Eigen::RowMajor>;

struct QuadraticMesh {
  RowVectors3d points;                   // corners (same ids as the linear mesh), then edges
  Tet10Cells cells;                      // m x 10
  std::vector<std::array<int, 2>> edges; // edge e is node numCorners + e, between these corners
  std::vector<char> boundaryEdge;        // edge lies on the boundary of the linear mesh
  Eigen::Index numCorners = 0;
};

// Builds the TET10 mesh; `projection` (may be empty) moves the mid-edge nodes of boundary edges.
// Fails when the node ids would overflow 32-bit ints.
Status MakeQuadraticMesh(const TetMesh& mesh, QuadraticMesh& out,
                         const MidEdgeProjection& projection = {});

using Tet10Nodes = Eigen::Matrix<double, 10, 3>;
using Tet10Matrix = Eigen::Matrix<double, 30, 30>;

// 30x30 stiffness of one (possibly curved) TET10, isoparametric, 4-point rule (exact for straight
// edges). DOF order (node0 x,y,z, node1 x,y,z, ...). `minJacobian` receives the smallest
// Jacobian determinant at the quadrature points (<= 0: the curved cell is invalid).
// meanDilatation: the volumetric (lambda) term uses the cell's mean divergence, lambda V bbar
// bbar^T with bbar = (1/V) int div N (the P2-P0 mixed element with the constant pressure
// condensed out: exact and symmetric). It keeps one incompressibility constraint per cell instead
// of four, which removes volumetric locking as nu -> 0.5; the shear (mu) term is fully integrated.
Tet10Matrix Tet10Stiffness(const Tet10Nodes& nodes, double E, double nu,
                           double* minJacobian = nullptr, bool meanDilatation = false);

// Integral of each shape function over the cell (the consistent load of a unit body force):
// -V/20 at corners and V/5 at mid-edge nodes for a straight cell.
Eigen::Matrix<double, 10, 1> Tet10ShapeIntegrals(const Tet10Nodes& nodes);

constexpr int kPackedTet10Size = 30 * 31 / 2; // 465

// Packed upper triangles of every cell (m x 465, row-major). Cells whose Jacobian is not positive
// somewhere are listed in `invalidCells`.
void ComputePackedTet10Stiffness(const QuadraticMesh& mesh, const Materials& materials,
                                 PackedElementMatrices& packed,
                                 std::vector<long long>& invalidCells, bool meanDilatation = false);

} // namespace faceplan
