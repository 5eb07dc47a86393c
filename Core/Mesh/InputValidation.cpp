// SPDX-License-Identifier: BSD-3-Clause
#include "Mesh/InputValidation.h"

#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"

namespace faceplan {

Status ValidateSolveInputs(const TetMesh& mesh, const Materials& materials, const NodeSets& sets) {
  Status status = ValidateMeshAndMaterials(mesh, materials);
  if (status)
    status = ValidateNodeSets(mesh, sets);
  if (status)
    status = CheckEveryComponentConstrained(mesh, sets.constrained);
  return status;
}

} // namespace faceplan
