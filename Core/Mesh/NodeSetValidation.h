// SPDX-License-Identifier: BSD-3-Clause
#pragma once
#include "Common/Status.h"
#include "Mesh/NodeSets.h"
#include "Mesh/TetMesh.h"

namespace faceplan {

// Node ids in range, at least one constrained node, ROI (movable) nodes all constrained.
Status ValidateNodeSets(const TetMesh& mesh, const NodeSets& sets);

} // namespace faceplan
