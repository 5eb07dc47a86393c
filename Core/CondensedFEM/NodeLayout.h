// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How the free and ROI DOF blocks are numbered, shared by the condensed solver and the other solve
// paths (FreeSystem), so both build the same blocks.
#include "CondensedFEM/CondensedFEM.h"

#include <vector>

namespace faceplan {

// Node numbering of the DOF blocks: free nodes first (kept, then interior), then ROI nodes.
// Constrained nodes outside the ROI and unused nodes have no DOFs (they never move). Sliding
// nodes are free nodes (their tangential DOFs are unknown); the normal value of a movable one is
// an extra ROI DOF after the 3 per ROI node.
struct NodeLayout {
  std::vector<int> dofNode;  // mesh node -> position in the blocks, -1 when it has no DOFs
  std::vector<int> meshNode; // position -> mesh node
  int keptFree = 0, interior = 0, roi = 0;
  int freeNodes() const { return keptFree + interior; }
  std::vector<int> roiPosition; // NodeSets::movable index -> ROI position (0-based within ROI)
  // NodeSets::movable index -> its normal value's ROI DOF (3 roi + k), -1 when not sliding.
  std::vector<int> slidingRoiDof;
  int slidingRoi = 0;
  int roiDofs() const { return 3 * roi + slidingRoi; }
};

// `used` marks the nodes some cell references (corner and, for quadratic cells, mid-edge nodes).
NodeLayout MakeLayout(const std::vector<char>& used, const NodeSets& sets);

// A sliding node's frame: columns n, t1, t2 (any orthonormal tangents will do: the tangential
// DOFs are both free).
Eigen::Matrix3d NormalFrame(const Eigen::Vector3d& normal);

} // namespace faceplan
