// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Structured tetrahedral meshes of a thick spherical shell, for verification and benchmarks:
// an icosahedral sphere (each icosahedron edge cut into `subdivisions` pieces) extruded into
// `layers` prism layers between radii, each prism split into 3 tetrahedra by the smallest-
// global-index rule, which keeps neighbouring splits conforming.
#include "Mesh/TetMesh.h"

#include <vector>

namespace faceplan {

struct ShellMesh {
  TetMesh mesh;
  std::vector<int> innerNodes; // on the inner sphere
  std::vector<int> outerNodes; // on the outer sphere
  int nodesPerLayer = 0;       // node i lies on layer i / nodesPerLayer (0 = inner)
};

ShellMesh MakeSphericalShell(int subdivisions, int layers, double innerRadius, double outerRadius);

// A face-like benchmark scene on the shell: inner surface tied to bone, an ROI cap holding about
// `roiFraction` of the inner nodes (around +z), outer surface kept.
struct FaceLikeScene {
  ShellMesh shell;
  std::vector<int> constrained, movable, kept;
};
FaceLikeScene MakeFaceLikeScene(int subdivisions, int layers, double roiFraction = 0.1);

} // namespace faceplan
