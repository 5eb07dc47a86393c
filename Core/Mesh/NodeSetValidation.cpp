// SPDX-License-Identifier: BSD-3-Clause
#include "Mesh/NodeSetValidation.h"

#include <cmath>
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
    if (!s)
      return s;
  if (sets.constrained.empty())
    return Status::Error("no constrained node: the tissue is tied to nothing, so its stiffness "
                         "matrix is singular");
  std::vector<char> constrained(n, 0);
  for (int id : sets.constrained)
    constrained[id] = 1;
  for (int id : sets.movable)
    if (!constrained[id])
      return Status::Error("ROI (movable) node " + std::to_string(id) +
                           " is not a constrained node");
  if (!sets.movableSegment.empty()) {
    if (sets.movableSegment.size() != sets.movable.size())
      return Status::Error("movableSegment needs one segment id per movable node (" +
                           std::to_string(sets.movable.size()) + "), got " +
                           std::to_string(sets.movableSegment.size()));
    for (int segment : sets.movableSegment)
      if (segment < 0)
        return Status::Error("segment id " + std::to_string(segment) + " is negative");
  }
  if (sets.slidingNormal.size() != sets.sliding.size())
    return Status::Error("slidingNormal needs one normal per sliding node (" +
                         std::to_string(sets.sliding.size()) + "), got " +
                         std::to_string(sets.slidingNormal.size()));
  if (Status s = check(sets.sliding, "sliding"); !s)
    return s;
  std::vector<char> sliding(n, 0);
  for (size_t k = 0; k < sets.sliding.size(); ++k) {
    const int id = sets.sliding[k];
    if (!constrained[id])
      return Status::Error("sliding node " + std::to_string(id) + " is not a constrained node");
    if (sliding[id])
      return Status::Error("sliding node " + std::to_string(id) + " is listed twice");
    sliding[id] = 1;
    const double norm = sets.slidingNormal[k].norm();
    if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-6)
      return Status::Error("the normal of sliding node " + std::to_string(id) +
                           " is not a finite unit vector");
  }
  return Status::Ok();
}

} // namespace faceplan
