// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/SupernodalTree.h"

#include <algorithm>

namespace faceplan {

Status NumericSupernodalStructure(const cholmod_factor& factor, SupernodalStructure& out) {
  if (!factor.is_super || !factor.is_ll || factor.xtype != CHOLMOD_REAL || !factor.x ||
      factor.itype != CHOLMOD_INT)
    return Status::Error(
        "internal: the pruned substitutions need a numeric supernodal LL^T factor");
  out.n = static_cast<int>(factor.n);
  out.nsuper = static_cast<int>(factor.nsuper);
  out.super = static_cast<const int*>(factor.super);
  out.pi = static_cast<const int*>(factor.pi);
  out.s = static_cast<const int*>(factor.s);
  return Status::Ok();
}

std::vector<int> SupernodeOfColumns(const SupernodalStructure& tree) {
  std::vector<int> supernodeOf(tree.n);
  for (int k = 0; k < tree.nsuper; ++k)
    std::fill(supernodeOf.begin() + tree.super[k], supernodeOf.begin() + tree.super[k + 1], k);
  return supernodeOf;
}

std::vector<int> SupernodeParents(const SupernodalStructure& tree,
                                  const std::vector<int>& supernodeOf) {
  std::vector<int> parent(tree.nsuper, -1);
  for (int k = 0; k < tree.nsuper; ++k) {
    const SupernodeShape shape = tree.shape(k);
    if (shape.offDiagonal > 0)
      parent[k] = supernodeOf[tree.s[tree.pi[k] + shape.columns]];
  }
  return parent;
}

Status MarkSupernodesAbove(const SupernodalStructure& tree, const std::vector<int>& rows,
                           std::vector<char>& marked) {
  const std::vector<int> supernodeOf = SupernodeOfColumns(tree);
  const std::vector<int> parent = SupernodeParents(tree, supernodeOf);
  marked.assign(tree.nsuper, rows.empty() ? 1 : 0);
  for (int p : rows) {
    if (p < 0 || p >= tree.n)
      return Status::Error("internal: a row outside the factor");
    marked[supernodeOf[p]] = 1;
  }
  for (int k = 0; k < tree.nsuper; ++k)
    if (marked[k] && parent[k] >= 0)
      marked[parent[k]] = 1;
  return Status::Ok();
}

} // namespace faceplan
