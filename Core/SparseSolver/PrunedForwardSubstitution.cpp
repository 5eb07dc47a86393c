#include "SparseSolver/PrunedForwardSubstitution.h"
#include "SparseSolver/Blas.h"

#include <algorithm>
#include <cholmod.h>

namespace faceplan {

Status PrunedForwardSubstitution::prepare(const cholmod_factor& factor,
                                          const std::vector<int>& nonZeroPositions) {
  if (!factor.is_super || !factor.is_ll || factor.xtype != CHOLMOD_REAL || !factor.x ||
      factor.itype != CHOLMOD_INT)
    return Status::Error("internal: forward substitution needs a numeric supernodal LL^T factor");
  factor_ = &factor;
  const int n = static_cast<int>(factor.n), nsuper = static_cast<int>(factor.nsuper);
  const int* super = static_cast<const int*>(factor.super);
  const int* pi = static_cast<const int*>(factor.pi);
  const int* s = static_cast<const int*>(factor.s);
  std::vector<int> supernodeOf(n);
  for (int k = 0; k < nsuper; ++k)
    std::fill(supernodeOf.begin() + super[k], supernodeOf.begin() + super[k + 1], k);
  reached_.assign(nsuper, 0);
  for (int p : nonZeroPositions) {
    if (p < 0 || p >= n)
      return Status::Error("internal: right-hand side row outside the factor");
    reached_[supernodeOf[p]] = 1;
  }
  supernodes_.clear();
  largestOffDiagonal_ = 0;
  flops_ = 0.0;
  for (int k = 0; k < nsuper; ++k) { // parents come later: one pass spreads the reach upwards
    if (!reached_[k])
      continue;
    const int columns = super[k + 1] - super[k], offDiagonal = pi[k + 1] - pi[k] - columns;
    if (offDiagonal > 0)
      reached_[supernodeOf[s[pi[k] + columns]]] = 1;
    supernodes_.push_back(k);
    largestOffDiagonal_ = std::max(largestOffDiagonal_, offDiagonal);
    flops_ += 2.0 * columns * offDiagonal + double(columns) * columns;
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
