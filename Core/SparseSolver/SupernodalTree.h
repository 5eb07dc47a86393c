// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The supernodal elimination tree of a supernodal Cholesky factor in CHOLMOD's layout, as the
// pruned substitutions (and the CUDA response's forward sweep) use it. For .cpp files only (CHOLMOD
// is a private dependency of FacePlanSparseSolver).
#include "Common/Status.h"

#include <cholmod.h>
#include <vector>

namespace faceplan {

// Columns and off-diagonal rows of a supernode, and the flops of one right-hand side's
// substitution through it (triangular solve plus the off-diagonal product).
struct SupernodeShape {
  int columns = 0, offDiagonal = 0;
  double flops() const { return 2.0 * columns * offDiagonal + double(columns) * columns; }
};

// CHOLMOD's supernode arrays: first column of each supernode (super), start of its row list (pi),
// and the row lists (s).
struct SupernodalStructure {
  int n = 0, nsuper = 0;
  const int* super = nullptr;
  const int* pi = nullptr;
  const int* s = nullptr;
  SupernodeShape shape(int k) const {
    const int columns = super[k + 1] - super[k];
    return {columns, pi[k + 1] - pi[k] - columns};
  }
};

// The structure of a numeric, supernodal LL^T factor; fails for any other.
Status NumericSupernodalStructure(const cholmod_factor& factor, SupernodalStructure& out);

// The supernode holding each column of the factor.
std::vector<int> SupernodeOfColumns(const SupernodalStructure& tree);

// Each supernode's parent in the tree: the supernode of its first off-diagonal row, always later in
// the order; -1 for a root. supernodeOf as SupernodeOfColumns gives it.
std::vector<int> SupernodeParents(const SupernodalStructure& tree,
                                  const std::vector<int>& supernodeOf);

// marked[k] = 1 for every supernode k that holds one of `rows` or lies above one in the tree;
// every supernode when `rows` is empty. A supernode's parent is the supernode of its first
// off-diagonal row, always later in the order, so one ascending pass suffices. Fails for a row
// outside the factor.
Status MarkSupernodesAbove(const SupernodalStructure& tree, const std::vector<int>& rows,
                           std::vector<char>& marked);

} // namespace faceplan
