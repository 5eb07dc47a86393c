#pragma once
// Scenes for Core's tests, all built by Core's generator.
#include "CondensedFEM/CondensedFEM.h"
#include "Support/ShellMeshGenerator.h"

namespace faceplan::testing {

// Shell scene: inner surface constrained, an ROI cap movable, outer surface kept.
PrecomputeRequest ShellRequest(int subdivisions, int layers, double E = 3000.0, double nu = 0.45);

// A smooth, non-trivial ROI displacement field (mm) for the request's movable nodes.
RowVectors3d SmoothRoiField(const PrecomputeRequest& request, double amplitude = 2.0);

} // namespace faceplan::testing
