#pragma once
// The supernodal elimination tree of a CHOLMOD factor, as the pruned substitutions use it. For .cpp
// files only (CHOLMOD is a private dependency of FacePlanSparseSolver).
#include "Common/Status.h"

#include <cholmod.h>
#include <vector>

namespace faceplan {

// marked[k] = 1 for every supernode k that holds one of `rows` (elimination positions) or lies
// above one in the tree; every supernode when `rows` is empty. A supernode's parent is the
// supernode of its first off-diagonal row, always later in the order, so one ascending pass
// suffices. Fails unless the factor is numeric, supernodal and LL^T, or a row is outside it.
Status MarkSupernodesAbove(const cholmod_factor& factor, const std::vector<int>& rows,
                           std::vector<char>& marked);

// Columns and off-diagonal rows of supernode k, and the flops of one right-hand side's
// substitution through it (triangular solve plus the off-diagonal product).
struct SupernodeShape {
  int columns = 0, offDiagonal = 0;
  double flops() const { return 2.0 * columns * offDiagonal + double(columns) * columns; }
};
SupernodeShape ShapeOf(const cholmod_factor& factor, int k);

} // namespace faceplan
