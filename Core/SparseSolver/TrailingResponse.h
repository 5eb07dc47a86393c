#pragma once
// The dense response -(rows [0, keptDofs) of K_FF^-1 K_FR) from a factor whose ordering put the
// DOFs coupled to the ROI last (CholmodFactor::solveTrailing): one backward substitution per ROI
// DOF instead of a full solve, column blocks spread over the cores.
//
// Accuracy is checked without a residual per column (a sparse product with every column costs
// about as much as the backward substitutions here): the solutions are also combined with a few
// random +-1 weight vectors w while they are in memory, and ||K_FF X w - K_FR w|| / ||K_FR w|| is
// evaluated for each. That estimates the relative residual an edit sees (it is the root mean
// square of the column residuals in expectation, not a bound on the largest); the caller redoes
// the response with per-column residuals and refinement when the estimate misses its tolerance.
#include "SparseSolver/CholmodFactor.h"
#include "Common/Status.h"

#include <atomic>
#include <functional>

namespace faceplan {

struct TrailingResponseResult {
  Eigen::MatrixXd response;      // keptDofs x ROI DOFs
  double residualEstimate = 0.0; // largest relative residual over the random probes
  int probes = 0;
};

// `blockColumns`: largest column block per solve; `progress(fraction)` is called after each block
// (fraction of blocks done). Returns "cancelled" when `cancel` becomes true.
Status BuildTrailingResponse(const CholmodFactor& factor, const SparseMatrix& kffUpper,
                             const SparseMatrix& kfr, Eigen::Index keptDofs,
                             Eigen::Index blockColumns, const std::atomic<bool>* cancel,
                             const std::function<void(double)>& progress,
                             TrailingResponseResult& out);

} // namespace faceplan
