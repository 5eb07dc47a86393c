// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A structured tetrahedral mesh of the box [0, lx] x [0, ly] x [0, lz]: nx * ny * nz hexahedra,
// each split into 6 tetrahedra around its main diagonal (Kuhn split, conforming between
// neighbours).
#include "Mesh/TetMesh.h"

namespace faceplan {

// Node (i, j, k), 0 <= i <= nx, ..., has index i + (nx + 1) * (j + (ny + 1) * k).
TetMesh MakeBoxTetMesh(int nx, int ny, int nz, double lx, double ly, double lz);

} // namespace faceplan
