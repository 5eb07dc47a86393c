#pragma once
// Input checks shared by every entry point, each failing with a message that names the problem.
#include "Status.h"
#include "TetMesh.h"

#include <vector>

namespace faceplan {

// Coordinates finite, node ids in range, volumes positive (ids of the offenders listed),
// materials in range (E > 0, -1 < nu < 0.5).
Status ValidateMeshAndMaterials(const TetMesh& mesh, const Materials& materials);

// Connected components of the tetrahedra (sharing a node connects two cells).
// componentOfNode[i] is -1 for nodes used by no tetrahedron.
int ConnectedComponents(const TetMesh& mesh, std::vector<int>& componentOfNode);

// Every component must hold at least one constrained node, or the stiffness matrix is singular.
Status CheckEveryComponentConstrained(const TetMesh& mesh, const std::vector<int>& constrained);

} // namespace faceplan
