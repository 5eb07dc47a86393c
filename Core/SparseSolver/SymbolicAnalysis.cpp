// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/SymbolicAnalysis.h"

#include "SparseSolver/CholmodViews.h"

#include "Common/InversePermutation.h"
#include "Common/ParallelFor.h"
#include "Common/WorkerThreads.h"

#include <algorithm>
#include <thread>

namespace faceplan {

void ApplySupernodeRelaxation(cholmod_common& common, SupernodeRelaxation relaxation) {
  // CHOLMOD's defaults (cholmod_defaults), or coarser: at most 16/64/128 columns merged at up to
  // 90/30/10 % zeros. The CPU's multifrontal factorization is faster with CHOLMOD's own; the GPU's
  // per-supernode costs favour the coarser setting.
  const bool coarse = relaxation == SupernodeRelaxation::Coarse;
  const size_t nrelax[3] = {coarse ? 16u : 4u, coarse ? 64u : 16u, coarse ? 128u : 48u};
  const double zrelax[3] = {coarse ? 0.9 : 0.8, coarse ? 0.3 : 0.1, coarse ? 0.1 : 0.05};
  for (int k = 0; k < 3; ++k) {
    common.nrelax[k] = nrelax[k];
    common.zrelax[k] = zrelax[k];
  }
}

namespace {

// The upper triangle's pattern of A(perm, perm) for a CSC pattern (start, index) of n columns,
// `inverse` = DOF -> position: a parallel counting sort, each thread counting and placing the
// entries of its own range of columns (rows unsorted, in the same order on every run).
void PermutedUpperPattern(int n, const int* start, const int* index,
                          const std::vector<int>& inverse, std::vector<int>& columnStart,
                          std::vector<int>& rows) {
  const int threads = std::max(1, std::min(WorkerThreads(16), n / 20000 + 1));
  const int chunk = (n + threads - 1) / threads;
  std::vector<std::vector<int>> count(threads);
  auto inParallel = [&](auto&& work) {
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t)
      pool.emplace_back(work, t);
    work(0);
    for (std::thread& thread : pool)
      thread.join();
  };
  auto forEntries = [&](int t, auto&& visit) {
    for (int j = t * chunk; j < std::min(n, (t + 1) * chunk); ++j)
      for (int k = start[j]; k < start[j + 1]; ++k) {
        const int a = inverse[index[k]], b = inverse[j];
        visit(std::max(a, b), std::min(a, b)); // (column, row) in the permuted upper triangle
      }
  };
  inParallel([&](int t) {
    count[t].assign(n, 0);
    forEntries(t, [&](int column, int) { ++count[t][column]; });
  });
  // Offsets: column by column, thread by thread within a column.
  columnStart.assign(static_cast<size_t>(n) + 1, 0);
  int next = 0;
  for (int c = 0; c < n; ++c) {
    columnStart[c] = next;
    for (int t = 0; t < threads; ++t) {
      const int here = count[t][c];
      count[t][c] = next;
      next += here;
    }
  }
  columnStart[n] = next;
  rows.resize(next);
  inParallel(
      [&](int t) { forEntries(t, [&](int column, int row) { rows[count[t][column]++] = row; }); });
}

// The node graph's strictly upper pattern (CSC over nodes) when `upper` is node-blocked: column
// 3c+d holds exactly rows 3r..3r+2 of each neighbour node r < c and rows 3c..3c+d. False otherwise.
bool NodeGraphOfBlockedMatrix(const SparseMatrix& upper, std::vector<int>& nodeStart,
                              std::vector<int>& nodeRows) {
  const int n = static_cast<int>(upper.rows());
  if (n % 3 != 0 || upper.cols() != n || !upper.isCompressed())
    return false;
  const int nodes = n / 3;
  const int* start = upper.outerIndexPtr();
  const int* index = upper.innerIndexPtr();
  std::vector<std::vector<int>> neighbours(nodes);
  std::vector<char> blocked(nodes, 1);
  ParallelFor(nodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    std::vector<int> rows, expected;
    for (std::int64_t c = begin; c < end; ++c) {
      std::vector<int>& below = neighbours[c];
      for (int d = 0; d < 3 && blocked[c]; ++d) {
        const int column = static_cast<int>(3 * c + d);
        rows.assign(index + start[column], index + start[column + 1]);
        if (!std::is_sorted(rows.begin(), rows.end()))
          std::sort(rows.begin(), rows.end());
        if (d == 0) { // the neighbour nodes, from the first column
          for (int row : rows)
            if (row < 3 * c && (below.empty() || below.back() != row / 3))
              below.push_back(row / 3);
        }
        expected.clear();
        for (int r : below)
          for (int e = 0; e < 3; ++e)
            expected.push_back(3 * r + e);
        for (int e = 0; e <= d; ++e)
          expected.push_back(static_cast<int>(3 * c + e));
        blocked[c] = rows == expected;
      }
    }
  });
  if (std::find(blocked.begin(), blocked.end(), 0) != blocked.end())
    return false;
  nodeStart.assign(static_cast<size_t>(nodes) + 1, 0);
  for (int c = 0; c < nodes; ++c)
    nodeStart[c + 1] = nodeStart[c] + static_cast<int>(neighbours[c].size());
  nodeRows.resize(nodeStart[nodes]);
  ParallelFor(nodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t c = begin; c < end; ++c)
      std::copy(neighbours[c].begin(), neighbours[c].end(), nodeRows.begin() + nodeStart[c]);
  });
  return true;
}

// The DOF-level upper pattern of a node graph's strictly upper pattern (CSC over nodes): column
// 3c+d holds rows 3r..3r+2 of each node r of column c, then 3c..3c+d.
void ExpandNodePattern(int nodes, const std::vector<int>& nodeStart,
                       const std::vector<int>& nodeRows, std::vector<int>& columnStart,
                       std::vector<int>& rows) {
  columnStart.assign(3 * static_cast<size_t>(nodes) + 1, 0);
  for (int c = 0; c < nodes; ++c) {
    const int below = 3 * (nodeStart[c + 1] - nodeStart[c]);
    for (int d = 0; d < 3; ++d)
      columnStart[3 * c + d + 1] = columnStart[3 * c + d] + below + d + 1;
  }
  rows.resize(columnStart.back());
  ParallelFor(nodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t c = begin; c < end; ++c)
      for (int d = 0; d < 3; ++d) {
        int k = columnStart[3 * c + d];
        for (int p = nodeStart[c]; p < nodeStart[c + 1]; ++p)
          for (int e = 0; e < 3; ++e)
            rows[k++] = 3 * nodeRows[p] + e;
        for (int e = 0; e <= d; ++e)
          rows[k++] = static_cast<int>(3 * c + e);
      }
  });
}

// The node order of a DOF order that keeps each node's three DOFs together and in order; empty
// when it does not.
std::vector<int> NodeOrderOf(const std::vector<int>& perm) {
  const size_t nodes = perm.size() / 3;
  std::vector<int> order(nodes);
  for (size_t k = 0; k < nodes; ++k) {
    const int first = perm[3 * k];
    if (first % 3 != 0 || perm[3 * k + 1] != first + 1 || perm[3 * k + 2] != first + 2)
      return {};
    order[k] = first / 3;
  }
  return order;
}

// The fast path (see the header): null when the matrix or the order is not node-blocked, or when
// a CHOLMOD call fails (the caller then lets CHOLMOD analyse, which reports its own failure).
cholmod_factor* AnalyzeNodeBlocked(const SparseMatrix& upper, const std::vector<int>& perm,
                                   cholmod_common& common) {
  const int n = static_cast<int>(upper.rows());
  // Supernodal only (what CholmodFactor asks for); other settings take CHOLMOD's own path.
  if (n == 0 || n % 3 != 0 || common.supernodal != CHOLMOD_SUPERNODAL)
    return nullptr;
  const std::vector<int> nodeOrder = NodeOrderOf(perm);
  std::vector<int> nodeStart, nodeRows;
  if (nodeOrder.empty() || !NodeGraphOfBlockedMatrix(upper, nodeStart, nodeRows))
    return nullptr;
  const int nodes = n / 3;

  // Elimination tree and column counts of the node graph in the node order.
  std::vector<int> permutedStart, permutedRows, dummyRow(1, 0);
  PermutedUpperPattern(nodes, nodeStart.data(), nodeRows.data(), InversePermutation(nodeOrder),
                       permutedStart, permutedRows);
  cholmod_sparse nodeGraph = ViewPattern(nodes, permutedStart, permutedRows, dummyRow);
  std::vector<int> nodeParent(nodes), nodePost(nodes), nodeCount(nodes), first(nodes), level(nodes);
  if (!cholmod_analyze_ordering(&nodeGraph, CHOLMOD_NATURAL, nullptr, nullptr, 0, nodeParent.data(),
                                nodePost.data(), nodeCount.data(), first.data(), level.data(),
                                &common))
    return nullptr;

  // Expanded to DOFs (positions in `perm`'s order), then CHOLMOD's weighted postorder.
  std::vector<int> parent(n), count(n), post(n);
  for (int r = 0; r < nodes; ++r)
    for (int d = 0; d < 3; ++d) {
      parent[3 * r + d] = d < 2 ? 3 * r + d + 1 : (nodeParent[r] < 0 ? -1 : 3 * nodeParent[r]);
      count[3 * r + d] = 3 * nodeCount[r] - d;
    }
  if (cholmod_postorder(parent.data(), n, count.data(), post.data(), &common) != n)
    return nullptr;
  std::vector<int> finalPerm(n), finalCount(n), finalParent(n), positionOf(n);
  for (int k = 0; k < n; ++k) {
    finalPerm[k] = perm[post[k]];
    finalCount[k] = count[post[k]];
    positionOf[post[k]] = k;
  }
  for (int k = 0; k < n; ++k) {
    const int old = parent[post[k]];
    finalParent[k] = old < 0 ? -1 : positionOf[old];
  }

  // The supernodal pattern, by CHOLMOD, from the pattern in the final order: the postorder keeps
  // each node's DOFs together (a node's three DOFs are a chain), so the node graph permuted again
  // and expanded gives it.
  std::vector<int> columnStart, rows;
  const std::vector<int> finalNodeOrder = NodeOrderOf(finalPerm);
  if (finalNodeOrder.empty())
    return nullptr; // cannot happen (see above)
  PermutedUpperPattern(nodes, nodeStart.data(), nodeRows.data(), InversePermutation(finalNodeOrder),
                       permutedStart, permutedRows);
  ExpandNodePattern(nodes, permutedStart, permutedRows, columnStart, rows);
  cholmod_sparse permuted = ViewPattern(n, columnStart, rows, dummyRow);
  cholmod_factor* L = cholmod_allocate_factor(n, &common);
  if (!L)
    return nullptr;
  std::copy(finalPerm.begin(), finalPerm.end(), static_cast<int*>(L->Perm));
  std::copy(finalCount.begin(), finalCount.end(), static_cast<int*>(L->ColCount));
  L->ordering = CHOLMOD_GIVEN;
  if (!cholmod_super_symbolic(&permuted, nullptr, finalParent.data(), L, &common)) {
    cholmod_free_factor(&L, &common);
    return nullptr;
  }
  double lnz = 0.0, fl = 0.0; // as cholmod_rowcolcounts reports them
  for (int k = 0; k < n; ++k) {
    lnz += finalCount[k];
    fl += double(finalCount[k]) * finalCount[k];
  }
  common.lnz = lnz;
  common.fl = fl;
  return L;
}

} // namespace

cholmod_factor* AnalyzeInGivenOrder(const SparseMatrix& upper, const std::vector<int>& perm,
                                    cholmod_common& common, bool* nodeBlocked) {
  if (cholmod_factor* L = AnalyzeNodeBlocked(upper, perm, common)) {
    if (nodeBlocked)
      *nodeBlocked = true;
    return L;
  }
  if (nodeBlocked)
    *nodeBlocked = false;
  const int n = static_cast<int>(upper.rows());
  std::vector<int> columnStart, rows, dummyRow(1, 0);
  PermutedUpperPattern(n, upper.outerIndexPtr(), upper.innerIndexPtr(), InversePermutation(perm),
                       columnStart, rows);
  cholmod_sparse view = ViewPattern(n, columnStart, rows, dummyRow);
  // Only the natural order of the permuted copy, then CHOLMOD's postorder (the caller's choices
  // of methods are put back after).
  const int methods = common.nmethods, ordering = common.method[0].ordering,
            postorder = common.postorder;
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_NATURAL;
  common.postorder = 1;
  cholmod_factor* L = cholmod_analyze(&view, &common);
  common.nmethods = methods;
  common.method[0].ordering = ordering;
  common.postorder = postorder;
  if (!L)
    return nullptr;
  int* position = static_cast<int*>(L->Perm); // into the permuted copy: back to `upper`'s DOFs
  for (int k = 0; k < n; ++k)
    position[k] = perm[position[k]];
  L->ordering = CHOLMOD_GIVEN; // factorize and solve permute by L->Perm unless NATURAL
  return L;
}

} // namespace faceplan
