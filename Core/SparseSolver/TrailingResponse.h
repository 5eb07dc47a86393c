// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The dense response -(rows [0, keptDofs) of K_FF^-1 K_FR) from a factor whose ordering put the
// DOFs coupled to the ROI last: the forward substitution is a dense triangular solve with the
// factor's trailing block, and the backward substitution visits only the supernodes the kept rows
// depend on (PrunedBackSubstitution), with column blocks spread over the cores.
//
// Accuracy is checked without a residual per column (a sparse product with every column costs
// about as much as the substitutions here): for a few random +-1 weight vectors w, K_FF z = K_FR w
// is solved on every row with the same triangular solves, z's kept rows are replaced by the
// response's own prediction, and the relative residual of that vector is evaluated. That estimates
// the relative residual an edit sees (the root mean square of the column residuals in
// expectation, not a bound on the largest) and shows any kept row the pruned solve got wrong; the
// caller redoes the response with per-column residuals and refinement when it misses its tolerance.
#include "Common/Status.h"
#include "SparseSolver/CholmodFactor.h"

#include <atomic>
#include <functional>

namespace faceplan {

struct TrailingResponseResult {
  Eigen::MatrixXd response;      // keptDofs x ROI DOFs
  double residualEstimate = 0.0; // largest relative residual over the random probes
  int probes = 0;
  // Flops of the backward substitution restricted to the kept rows' supernodes, over those of the
  // whole backward substitution.
  double backwardFlopsFraction = 1.0;
  // Without a trailing block: flops of the forward substitution over the reach of the coupled
  // rows, over those of a whole backward substitution (0 with a trailing block).
  double forwardFlopsFraction = 0.0;
};

// `blockColumns`: largest column block per solve; `progress(fraction)` is called after each block
// (fraction of blocks done). Returns "cancelled" when `cancel` becomes true.
Status BuildTrailingResponse(const CholmodFactor& factor, const SparseMatrix& kffUpper,
                             const SparseMatrix& kfr, Eigen::Index keptDofs,
                             Eigen::Index blockColumns, const std::atomic<bool>* cancel,
                             const std::function<void(double)>& progress,
                             TrailingResponseResult& out);

} // namespace faceplan
