// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/PrunedForwardSubstitution.h"
#include "SparseSolver/Blas.h"
#include "SparseSolver/SupernodalTree.h"

#include <algorithm>
#include <cholmod.h>

namespace faceplan {

Status PrunedForwardSubstitution::prepare(const cholmod_factor& factor,
                                          const std::vector<int>& nonZeroPositions) {
  SupernodalStructure tree;
  if (Status s = NumericSupernodalStructure(factor, tree); !s)
    return s;
  if (Status s = MarkSupernodesAbove(tree, nonZeroPositions, reached_); !s)
    return s;
  factor_ = &factor;
  supernodes_.clear();
  largestOffDiagonal_ = 0;
  flops_ = 0.0;
  for (int k = 0; k < tree.nsuper; ++k) {
    if (!reached_[k])
      continue;
    const SupernodeShape shape = tree.shape(k);
    supernodes_.push_back(k);
    largestOffDiagonal_ = std::max(largestOffDiagonal_, shape.offDiagonal);
    flops_ += shape.flops();
  }
  return Status::Ok();
}

void PrunedForwardSubstitution::clearReach(double* x, int columns) const {
  const int* super = static_cast<const int*>(factor_->super);
  for (int k : supernodes_)
    std::fill(x + size_t(super[k]) * columns, x + size_t(super[k + 1]) * columns, 0.0);
}

void PrunedForwardSubstitution::solve(double* x, int columns, std::vector<double>& scratch) const {
  const int* super = static_cast<const int*>(factor_->super);
  const int* pi = static_cast<const int*>(factor_->pi);
  const int* px = static_cast<const int*>(factor_->px);
  const int* s = static_cast<const int*>(factor_->s);
  const double* values = static_cast<const double*>(factor_->x);
  scratch.resize(size_t(largestOffDiagonal_) * columns);
  const double one = 1.0, zero = 0.0;
  for (int k : supernodes_) {
    const int first = super[k], width = super[k + 1] - first;
    const int height = pi[k + 1] - pi[k], offDiagonal = height - width;
    double* block = x + size_t(first) * columns;
    const double* diagonal = values + px[k];
    // Row-major X_k is the column-major X_k^T: X_k^T := X_k^T L_kk^-T, i.e. X_k := L_kk^-1 X_k.
    dtrsm_("R", "L", "T", "N", &columns, &width, &one, diagonal, &height, block, &columns);
    if (offDiagonal == 0)
      continue;
    // X_off -= L_off X_k, as U^T = X_k^T L_off^T (columns x offDiagonal), then scattered.
    double* update = scratch.data();
    dgemm_("N", "T", &columns, &offDiagonal, &width, &one, block, &columns, diagonal + width,
           &height, &zero, update, &columns);
    const int* rows = s + pi[k] + width;
    for (int r = 0; r < offDiagonal; ++r) {
      double* target = x + size_t(rows[r]) * columns;
      const double* source = update + size_t(r) * columns;
      for (int c = 0; c < columns; ++c)
        target[c] -= source[c];
    }
  }
}

} // namespace faceplan
