// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Backward substitution X := L^-T X with a CHOLMOD supernodal LL^T factor, for a block of
// right-hand sides stored row by row (the block's values of one row side by side, so that gathering
// a supernode's off-diagonal rows reads contiguous memory instead of one cache line per column),
// restricted to the rows the caller wants: a row's value depends only on the supernodes above it
// in the supernodal elimination tree, so a supernode whose subtree holds no wanted row is skipped.
// The dense response needs the kept (skin) rows only; CHOLMOD's own solve computes every row.
#include "Common/Status.h"

#include <vector>

struct cholmod_factor_struct;

namespace faceplan {

class PrunedBackSubstitution {
public:
  // `factor`: numeric, supernodal, LL^T. `wantedPositions`: rows (in elimination order) whose
  // values are needed; empty means all rows.
  Status prepare(const cholmod_factor_struct& factor, const std::vector<int>& wantedPositions);

  // x: n rows of `columns` values each (row-major). On entry rows [firstNonZero, n) hold L^-1 b and
  // rows above firstNonZero are taken as zero without being read (the caller need not clear them),
  // as are the rows of supernodes k with `reached` given and (*reached)[k] false (those outside a
  // PrunedForwardSubstitution's reach).
  // On exit the rows of every supernode that a wanted row depends on hold L^-T L^-1 b; the other
  // rows are undefined. `scratch` is a per-thread workspace. Not thread-safe per `x`; the object
  // itself is only read, so threads may share it.
  void solve(double* x, int columns, int firstNonZero, std::vector<double>& scratch,
             const std::vector<char>* reached = nullptr) const;

  // Flops per right-hand side of the pruned solve and of the whole backward substitution.
  double flopsPerColumn() const { return prunedFlops_; }
  double fullFlopsPerColumn() const { return fullFlops_; }
  int rows() const { return n_; }

private:
  const cholmod_factor_struct* factor_ = nullptr;
  int n_ = 0;
  std::vector<int> supernodes_; // the supernodes to visit, in decreasing order
  int largestOffDiagonal_ = 0;
  double prunedFlops_ = 0.0, fullFlops_ = 0.0;
};

} // namespace faceplan
