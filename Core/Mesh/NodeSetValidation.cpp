#include "Mesh/NodeSetValidation.h"

#include <string>

namespace faceplan {

Status ValidateNodeSets(const TetMesh& mesh, const NodeSets& sets) {
  const Eigen::Index n = mesh.numPoints();
  auto check = [n](const std::vector<int>& ids, const char* what) -> Status {
    for (int id : ids)
      if (id < 0 || id >= n)
        return Status::Error(std::string(what) + " node id " + std::to_string(id) +
                             " is out of range (the mesh has " + std::to_string(n) + " points)");
    return Status::Ok();
  };
  for (Status s : {check(sets.constrained, "constrained"), check(sets.movable, "ROI (movable)"),
                   check(sets.kept, "kept")})
    if (!s) return s;
  if (sets.constrained.empty())
    return Status::Error("no constrained node: the tissue is tied to nothing, so its stiffness "
                         "matrix is singular");
  std::vector<char> constrained(n, 0);
  for (int id : sets.constrained) constrained[id] = 1;
  for (int id : sets.movable)
    if (!constrained[id])
      return Status::Error("ROI (movable) node " + std::to_string(id) + " is not a constrained node");
  return Status::Ok();
}

} // namespace faceplan
