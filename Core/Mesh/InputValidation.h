// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The input check every solve path runs first: mesh and materials, node sets, and at least one
// constrained node in every connected component (otherwise the stiffness matrix is singular).
#include "Common/Status.h"
#include "Mesh/NodeSets.h"
#include "Mesh/TetMesh.h"

namespace faceplan {

Status ValidateSolveInputs(const TetMesh& mesh, const Materials& materials, const NodeSets& sets);

} // namespace faceplan
