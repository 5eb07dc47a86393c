#include "SparseSolver/SupernodalTree.h"

#include <algorithm>

namespace faceplan {

SupernodeShape ShapeOf(const cholmod_factor& factor, int k) {
  const int* super = static_cast<const int*>(factor.super);
  const int* pi = static_cast<const int*>(factor.pi);
  SupernodeShape shape;
  shape.columns = super[k + 1] - super[k];
  shape.offDiagonal = pi[k + 1] - pi[k] - shape.columns;
  return shape;
}

Status MarkSupernodesAbove(const cholmod_factor& factor, const std::vector<int>& rows,
                           std::vector<char>& marked) {
  if (!factor.is_super || !factor.is_ll || factor.xtype != CHOLMOD_REAL || !factor.x ||
      factor.itype != CHOLMOD_INT)
    return Status::Error("internal: the pruned substitutions need a numeric supernodal LL^T factor");
  const int n = static_cast<int>(factor.n), nsuper = static_cast<int>(factor.nsuper);
  const int* super = static_cast<const int*>(factor.super);
  const int* pi = static_cast<const int*>(factor.pi);
  const int* s = static_cast<const int*>(factor.s);
  std::vector<int> supernodeOf(n);
  for (int k = 0; k < nsuper; ++k)
    std::fill(supernodeOf.begin() + super[k], supernodeOf.begin() + super[k + 1], k);
  marked.assign(nsuper, rows.empty() ? 1 : 0);
  for (int p : rows) {
    if (p < 0 || p >= n)
      return Status::Error("internal: a row outside the factor");
    marked[supernodeOf[p]] = 1;
  }
  for (int k = 0; k < nsuper; ++k) {
    const SupernodeShape shape = ShapeOf(factor, k);
    if (marked[k] && shape.offDiagonal > 0)
      marked[supernodeOf[s[pi[k] + shape.columns]]] = 1;
  }
  return Status::Ok();
}

} // namespace faceplan
