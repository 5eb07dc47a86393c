// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scenes for Core's tests, all built by Core's generator.
#include "CondensedFEM/CondensedFEM.h"
#include "Support/ShellMeshGenerator.h"

namespace faceplan::testing {

// Shell scene: inner surface constrained, an ROI cap movable, outer surface kept.
PrecomputeRequest ShellRequest(int subdivisions, int layers, double E = 3000.0, double nu = 0.45);

// A smooth, non-trivial ROI displacement field (mm) for the request's movable nodes.
RowVectors3d SmoothRoiField(const PrecomputeRequest& request, double amplitude = 2.0);

// A block [0, lx] x [0, ly] x [0, lz] (5 x 4 x 3 hexahedra, Kuhn-split) on a frictionless floor
// (z = 0) under a frictionless plate (z = lz): both faces' nodes slide with normal z, those at
// z = lz are movable. Corner (0, 0, 0) is tied, and the nodes of the edge x = lx, y = 0 slide on
// the plane y = 0, which removes the rigid motions the walls leave. Every node is kept. Pressing
// the plate makes a homogeneous uniaxial state.
PrecomputeRequest PressedBlockRequest(double lx, double ly, double lz, double nu,
                                      double E = 3000.0);

// The plate of a PressedBlockRequest pressed down by `press` (mm), every node recovered.
SolveInput PlateMove(const PrecomputeRequest& request, double press);

// A thick spherical shell (radii 40 and 55): the bottom of its inner surface is tied, the rest of
// it slides on the sphere (sliding nodes with the radial normal), and a cap on top is pushed
// outwards along the normal by up to `push` (mm); the outer surface is free and kept. `moves` gets
// the cap's prescribed displacements (with a tangential part, which sliding nodes ignore).
PrecomputeRequest SlidingShellRequest(double push, RowVectors3d& moves);

} // namespace faceplan::testing
