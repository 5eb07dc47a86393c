// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The three node classes of a condensed FEM problem (indices into the tetrahedral mesh's points).
#include <Eigen/Core>

#include <vector>

namespace faceplan {

struct NodeSets {
  std::vector<int> constrained; // nodes with prescribed displacement
  std::vector<int> movable;     // subset of constrained: the ROI; the others are fixed at zero
  std::vector<int> kept;        // nodes reported by every solve (may include constrained nodes)

  // Rigid segments: empty, or one id per movable node (0 = moved by a general displacement,
  // k >= 1 = moved with rigid segment k by one affine motion u(x) = A x + b). With segments the
  // precompute can build the response to 12 motions per segment instead of one column per ROI DOF.
  std::vector<int> movableSegment;

  // Sliding contact: a subset of `constrained` whose displacement is prescribed only along the
  // unit normal (one per sliding node); the two tangential components are free.
  std::vector<int> sliding;
  std::vector<Eigen::Vector3d> slidingNormal;
};

} // namespace faceplan
