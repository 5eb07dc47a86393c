#pragma once
// The three node classes of a condensed FEM problem (indices into the tetrahedral mesh's points).
#include <vector>

namespace faceplan {

struct NodeSets {
  std::vector<int> constrained; // nodes with prescribed displacement
  std::vector<int> movable;     // subset of constrained: the ROI; the others are fixed at zero
  std::vector<int> kept;        // nodes reported by every solve (may include constrained nodes)
};

} // namespace faceplan
