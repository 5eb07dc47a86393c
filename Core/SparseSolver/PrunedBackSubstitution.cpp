// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/PrunedBackSubstitution.h"
#include "SparseSolver/Blas.h"
#include "SparseSolver/SupernodalTree.h"

#include <algorithm>
#include <cholmod.h>
#include <cstring>

namespace faceplan {

Status PrunedBackSubstitution::prepare(const cholmod_factor& factor,
                                       const std::vector<int>& wantedPositions) {
  SupernodalStructure tree;
  std::vector<char> needed; // the wanted rows' supernodes and everything above them
  if (Status s = NumericSupernodalStructure(factor, tree); !s)
    return s;
  if (Status s = MarkSupernodesAbove(tree, wantedPositions, needed); !s)
    return s;
  factor_ = &factor;
  n_ = static_cast<int>(factor.n);
  supernodes_.clear();
  largestOffDiagonal_ = 0;
  prunedFlops_ = fullFlops_ = 0.0;
  for (int k = tree.nsuper - 1; k >= 0; --k) {
    const SupernodeShape shape = tree.shape(k);
    fullFlops_ += shape.flops();
    if (!needed[k])
      continue;
    supernodes_.push_back(k);
    prunedFlops_ += shape.flops();
    largestOffDiagonal_ = std::max(largestOffDiagonal_, shape.offDiagonal);
  }
  return Status::Ok();
}

void PrunedBackSubstitution::solve(double* x, int columns, int firstNonZero,
                                   std::vector<double>& scratch,
                                   const std::vector<char>* reached) const {
  const int* super = static_cast<const int*>(factor_->super);
  const int* pi = static_cast<const int*>(factor_->pi);
  const int* px = static_cast<const int*>(factor_->px);
  const int* s = static_cast<const int*>(factor_->s);
  const double* values = static_cast<const double*>(factor_->x);
  scratch.resize(size_t(largestOffDiagonal_) * columns);
  const double minusOne = -1.0, one = 1.0, zero = 0.0;
  const size_t rowBytes = sizeof(double) * size_t(columns);
  for (int k : supernodes_) {
    const int first = super[k], width = super[k + 1] - first;
    const int height = pi[k + 1] - pi[k], offDiagonal = height - width;
    double* block = x + size_t(first) * columns; // this supernode's rows, contiguous
    const double* diagonal = values + px[k];
    // Rows above firstNonZero start as zero: clear them, or let the product overwrite them.
    const int zeroRows =
        reached && !(*reached)[k] ? width : std::clamp(firstNonZero - first, 0, width);
    double beta = 1.0;
    if (zeroRows == width && offDiagonal > 0)
      beta = 0.0;
    else if (zeroRows > 0)
      std::memset(block, 0, rowBytes * zeroRows);
    if (offDiagonal > 0) {
      // Gather x over the supernode's off-diagonal rows: contiguous rows of `columns` values.
      const int* rows = s + pi[k] + width;
      double* gathered = scratch.data();
      for (int r = 0; r < offDiagonal; ++r)
        std::memcpy(gathered + size_t(r) * columns, x + size_t(rows[r]) * columns, rowBytes);
      // Row-major X_k is the column-major X_k^T: X_k^T -= G^T L_off (G^T: columns x offDiagonal).
      dgemm_("N", "N", &columns, &width, &offDiagonal, &minusOne, gathered, &columns,
             diagonal + width, &height, beta == 0.0 ? &zero : &one, block, &columns);
    }
    // X_k^T := X_k^T L_kk^-1, i.e. X_k := L_kk^-T X_k.
    dtrsm_("R", "L", "N", "N", &columns, &width, &one, diagonal, &height, block, &columns);
  }
}

} // namespace faceplan
