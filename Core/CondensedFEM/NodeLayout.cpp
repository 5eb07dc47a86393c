// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/NodeLayout.h"
#include <Eigen/Geometry>

namespace faceplan {

NodeLayout MakeLayout(const std::vector<char>& used, const NodeSets& sets) {
  const Eigen::Index n = static_cast<Eigen::Index>(used.size());
  std::vector<char> constrained(n, 0), kept(n, 0);
  for (int i : sets.constrained)
    constrained[i] = 1;
  for (int i : sets.sliding)
    constrained[i] = 0; // free tangentially
  for (int i : sets.kept)
    kept[i] = 1;

  NodeLayout layout;
  layout.dofNode.assign(n, -1);
  auto place = [&](int node) {
    layout.dofNode[node] = static_cast<int>(layout.meshNode.size());
    layout.meshNode.push_back(node);
  };
  for (Eigen::Index i = 0; i < n; ++i)
    if (used[i] && !constrained[i] && kept[i])
      place(static_cast<int>(i));
  layout.keptFree = static_cast<int>(layout.meshNode.size());
  for (Eigen::Index i = 0; i < n; ++i)
    if (used[i] && !constrained[i] && !kept[i])
      place(static_cast<int>(i));
  layout.interior = static_cast<int>(layout.meshNode.size()) - layout.keptFree;
  std::vector<char> sliding(n, 0);
  for (int i : sets.sliding)
    sliding[i] = 1;
  layout.roiPosition.assign(sets.movable.size(), -1);
  layout.slidingRoiDof.assign(sets.movable.size(), -1);
  for (size_t k = 0; k < sets.movable.size(); ++k) {
    const int node = sets.movable[k];
    if (!used[node] || sliding[node])
      continue;
    if (layout.dofNode[node] < 0)
      place(node); // a repeated id keeps its first position
    layout.roiPosition[k] = layout.dofNode[node] - layout.freeNodes();
  }
  layout.roi = static_cast<int>(layout.meshNode.size()) - layout.freeNodes();
  std::vector<int> firstDof(n, -1); // a repeated id keeps its first DOF
  for (size_t k = 0; k < sets.movable.size(); ++k) {
    const int node = sets.movable[k];
    if (!used[node] || !sliding[node])
      continue;
    if (firstDof[node] < 0)
      firstDof[node] = 3 * layout.roi + layout.slidingRoi++;
    layout.slidingRoiDof[k] = firstDof[node];
  }
  return layout;
}

Eigen::Matrix3d NormalFrame(const Eigen::Vector3d& normal) {
  Eigen::Index axis;
  normal.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d t1 = normal.cross(Eigen::Vector3d::Unit(axis)).normalized();
  Eigen::Matrix3d frame;
  frame << normal, t1, normal.cross(t1);
  return frame;
}

} // namespace faceplan
