#pragma once
// How the free and ROI DOF blocks are numbered, shared by the condensed solver and the other solve
// paths (FreeSystem), so both build the same blocks.
#include "CondensedFEM/CondensedFEM.h"

#include <vector>

namespace faceplan {

// Node numbering of the DOF blocks: free nodes first (kept, then interior), then ROI nodes.
// Constrained nodes outside the ROI and unused nodes have no DOFs (they never move).
struct NodeLayout {
  std::vector<int> dofNode;  // mesh node -> position in the blocks, -1 when it has no DOFs
  std::vector<int> meshNode; // position -> mesh node
  int keptFree = 0, interior = 0, roi = 0;
  int freeNodes() const { return keptFree + interior; }
  std::vector<int> roiPosition; // NodeSets::movable index -> ROI position (0-based within ROI)
};

// `used` marks the nodes some cell references (corner and, for quadratic cells, mid-edge nodes).
NodeLayout MakeLayout(const std::vector<char>& used, const NodeSets& sets);

} // namespace faceplan
