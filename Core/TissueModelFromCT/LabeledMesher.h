// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The interface between the tissue model and a tetrahedral mesher of labelled images. The mesher
// itself (CGAL Mesh_3, GPL) lives in Core/Copyleft/CGAL and is passed in by the caller, so this
// part stays free of it.
#include "Common/Status.h"
#include "Mesh/TetMesh.h"
#include "TissueModelFromCT/LabelImage.h"

#include <atomic>
#include <functional>
#include <utility>
#include <vector>

namespace faceplan {

enum class MeshOptimiser { None, ODT, Lloyd };

struct MeshingParameters {
  double cellSize = 5.0;        // target tetrahedron edge length (image units, mm)
  double surfaceDistance = 2.0; // largest distance between a boundary facet and the interface
  double facetAngle = 25.0;     // smallest angle of a boundary triangle, degrees
  double radiusEdgeRatio = 3.0; // largest circumradius / shortest edge of a tetrahedron
  // Labels meshed with another target edge length (e.g. coarser bone, whose cells are dropped).
  std::vector<std::pair<int, double>> labelCellSize;
  MeshOptimiser optimiser = MeshOptimiser::Lloyd;
  double optimiserTimeLimit = 0.0; // seconds, 0 = no limit
  int optimiserIterations = 10;
  bool perturb = true;
  bool exude = true;
  double sliverBound = 5.0;      // smallest dihedral angle perturb and exude aim for, degrees
  unsigned int seed = 0;         // makes the result reproducible
  long long maximumVertices = 0; // hard cap on the refinement (0 = none)
};

// Tetrahedra of every non-zero label, positively oriented, in the image's physical frame.
struct LabeledTetMesh {
  TetMesh mesh;
  std::vector<int> tetLabel; // one per tetrahedron
};

using MeshingProgress = std::function<void(double fraction, const char* what)>;

// Meshes every non-zero label of `image`. `cancel` may be set from another thread; the mesher
// polls it and returns the error "cancelled".
using LabelMesher = std::function<Status(
    const LabelImage& image, const MeshingParameters& parameters, LabeledTetMesh& result,
    std::atomic<bool>* cancel, const MeshingProgress& progress)>;

} // namespace faceplan
