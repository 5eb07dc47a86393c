// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Forward substitution X := L^-1 X with a CHOLMOD supernodal LL^T factor for right-hand sides that
// are non-zero only on a few rows (a response column is non-zero only on the DOFs coupled to the
// ROI), on row-major blocks as in PrunedBackSubstitution: L^-1 b is non-zero only on the
// supernodes above those rows in the supernodal elimination tree (their "reach"), so only those
// are visited.
#include "Common/Status.h"

#include <vector>

struct cholmod_factor_struct;

namespace faceplan {

class PrunedForwardSubstitution {
public:
  // `nonZeroPositions`: rows (in elimination order) where right-hand sides may be non-zero.
  Status prepare(const cholmod_factor_struct& factor, const std::vector<int>& nonZeroPositions);
  // x: n rows of `columns` values each (row-major), zero outside the reach on entry (the caller
  // clears it once; rows outside the reach are never written). Scratch is a per-thread workspace.
  void solve(double* x, int columns, std::vector<double>& scratch) const;
  // Zeroes the rows of the reach (all that solve() reads or writes).
  void clearReach(double* x, int columns) const;
  // True for the supernodes in the reach (where L^-1 b may be non-zero).
  const std::vector<char>& reached() const { return reached_; }
  double flopsPerColumn() const { return flops_; }

private:
  const cholmod_factor_struct* factor_ = nullptr;
  std::vector<int> supernodes_; // the reach, in increasing order
  std::vector<char> reached_;
  int largestOffDiagonal_ = 0;
  double flops_ = 0.0;
};

} // namespace faceplan
