// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/FillReducingOrdering.h"

#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/MetisRandom.h"

#include "Common/WorkerThreads.h"

#include <algorithm>
#include <cholmod.h>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

namespace faceplan {

std::mutex& MetisMutex() {
  static std::mutex mutex;
  return mutex;
}

namespace {

// Upper-triangular pattern (CSC, strictly above the diagonal) of the node graph of the nodes
// with compact index >= 0, numbered by that index. visitNeighbours(node, f) calls f(neighbour)
// for each neighbour of lower or equal index, in increasing order (repeats allowed).
template <class VisitNeighbours>
void NodeGraphUpper(const std::vector<int>& compact, int compactNodes,
                    VisitNeighbours&& visitNeighbours, std::vector<int>& columnStart,
                    std::vector<int>& rows) {
  std::vector<int> lastSeen(compactNodes, -1);
  columnStart.assign(1, 0);
  rows.clear();
  const int nodes = static_cast<int>(compact.size());
  for (int node = 0; node < nodes; ++node) {
    const int column = compact[node];
    if (column < 0)
      continue;
    visitNeighbours(node, [&](int neighbour) {
      const int row = compact[neighbour];
      if (row < 0 || row >= column || lastSeen[row] == column)
        return;
      lastSeen[row] = column;
      rows.push_back(row);
    });
    columnStart.push_back(static_cast<int>(rows.size()));
  }
}

// Held around a METIS call unless every thread has its own METIS random generator.
std::unique_lock<std::mutex> LockMetisIfShared() {
  if (MetisRandomIsPerThread())
    return {};
  return std::unique_lock<std::mutex>(MetisMutex());
}

// METIS nested dissection of a graph (CSC upper pattern), AMD when METIS fails. With `depth` > 0
// and a graph large enough, the top levels are split here instead: a METIS node separator
// (cholmod_bisect), the two halves ordered at once on two threads (recursively), the separator
// last, which is the order METIS's own dissection gives its top levels. Each thread has its own
// cholmod_common and (MetisRandom.h) its own METIS random generator, so the ordering is the same
// on every run. `method` names what ordered the leaves; `leaves` counts the graphs METIS (or AMD)
// ordered whole.
constexpr int kParallelDissectionNodes = 10000;

Status OrderGraph(int n, std::vector<int>& columnStart, std::vector<int>& rows, int depth,
                  std::vector<int>& order, const char*& method, int& leaves) {
  leaves = 1;
  order.resize(n);
  std::vector<int> dummyRow(1, 0);
  cholmod_sparse graph = ViewPattern(n, columnStart, rows, dummyRow);
  QuietCholmodCommon quiet;
  cholmod_common& common = quiet.common;
  std::vector<int> part;
  if (depth > 0 && n >= kParallelDissectionNodes) {
    part.resize(n);
    SuiteSparse_long separator = -1;
    {
      std::unique_lock<std::mutex> metis = LockMetisIfShared();
      separator = cholmod_bisect(&graph, nullptr, 0, 1, part.data(), &common);
    }
    const long long left = std::count(part.begin(), part.end(), 0);
    if (separator < 0 || left == 0 || left + separator >= n)
      part.clear(); // no useful split: order the whole graph below
  }
  if (part.empty()) {
    method = "METIS";
    {
      std::unique_lock<std::mutex> metis = LockMetisIfShared();
      if (cholmod_metis(&graph, nullptr, 0, 0, order.data(), &common))
        return Status::Ok();
    }
    method = "AMD";
    common.status = CHOLMOD_OK;
    if (cholmod_amd(&graph, nullptr, 0, order.data(), &common))
      return Status::Ok();
    return Status::Error("fill-reducing ordering failed (CHOLMOD status " +
                         std::to_string(common.status) + ")");
  }
  // The two halves' induced subgraphs, nodes numbered in increasing order within each half.
  std::vector<int> local(n), halfNodes[2];
  for (int node = 0; node < n; ++node)
    if (part[node] < 2) {
      local[node] = static_cast<int>(halfNodes[part[node]].size());
      halfNodes[part[node]].push_back(node);
    }
  std::vector<int> halfStart[2], halfRows[2], halfOrder[2];
  for (int h = 0; h < 2; ++h) {
    halfStart[h].assign(1, 0);
    for (int node : halfNodes[h]) {
      for (int k = columnStart[node]; k < columnStart[node + 1]; ++k)
        if (part[rows[k]] == h)
          halfRows[h].push_back(local[rows[k]]);
      halfStart[h].push_back(static_cast<int>(halfRows[h].size()));
    }
  }
  Status halfStatus[2] = {Status::Ok(), Status::Ok()};
  const char* halfMethod[2] = {"METIS", "METIS"};
  int halfLeaves[2] = {1, 1};
  auto orderHalf = [&](int h) {
    halfStatus[h] = OrderGraph(static_cast<int>(halfNodes[h].size()), halfStart[h], halfRows[h],
                               depth - 1, halfOrder[h], halfMethod[h], halfLeaves[h]);
  };
  std::thread other(orderHalf, 1);
  orderHalf(0);
  other.join();
  for (int h = 0; h < 2; ++h)
    if (!halfStatus[h])
      return halfStatus[h];
  leaves = halfLeaves[0] + halfLeaves[1];
  method =
      std::string(halfMethod[0]) == "AMD" || std::string(halfMethod[1]) == "AMD" ? "AMD" : "METIS";
  size_t next = 0;
  for (int h = 0; h < 2; ++h)
    for (int k : halfOrder[h])
      order[next++] = halfNodes[h][k];
  for (int node = 0; node < n; ++node)
    if (part[node] == 2)
      order[next++] = node;
  return Status::Ok();
}

// Levels of the dissection split over threads for a graph of `nodes` nodes. `leaves` > 0 asks for
// that many (1, 2, 4, ... 64); 0 chooses: no split below kSplitFromNodes nodes, else up to 8
// leaves, as many as there are cores. Why not always: a split top costs some fill (its separator
// comes from one bisection, METIS's own dissection tries harder), which slows the factorization of
// a small mesh whose ordering is hidden beside the assembly anyway; on large meshes the ordering is
// the longest CPU path and the split factor is no larger. FACEPLAN_DISSECTION_LEAVES overrides the
// choice, for benchmarks.
constexpr int kSplitFromNodes = 50000;

int ParallelDissectionDepth(int nodes, int leaves) {
  int most = nodes >= kSplitFromNodes ? std::min(WorkerThreads(16), 8) : 1;
  if (leaves > 0)
    most = std::min(leaves, 64);
  else if (const char* text = std::getenv("FACEPLAN_DISSECTION_LEAVES");
           text && std::atoi(text) >= 1)
    most = std::min(std::atoi(text), 64);
  int depth = 0;
  for (int parts = 2; parts <= most; parts *= 2)
    ++depth;
  return depth;
}

} // namespace

std::vector<char> NodesCoupledTo(const SparseMatrix& coupling, int freeNodes, int dofsPerNode) {
  std::vector<char> coupled(freeNodes, 0);
  for (int c = 0; c < coupling.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(coupling, c); it; ++it)
      coupled[it.row() / dofsPerNode] = 1;
  return coupled;
}

namespace {

// Both entry points: the leading (unmarked) nodes by OrderGraph, the marked ones after them.
template <class VisitNeighbours>
Status OrderWithTrailing(int nodes, int dofsPerNode, const std::vector<char>& trailingNode,
                         VisitNeighbours&& visitNeighbours, FillReducingOrdering& ordering,
                         int leaves) {
  if (!trailingNode.empty() && static_cast<int>(trailingNode.size()) != nodes)
    return Status::Error("internal: trailing-node marks do not match the matrix");
  auto isTrailing = [&](int node) { return !trailingNode.empty() && trailingNode[node]; };

  std::vector<int> compact(nodes, -1), leading;
  for (int node = 0; node < nodes; ++node)
    if (!isTrailing(node)) {
      compact[node] = static_cast<int>(leading.size());
      leading.push_back(node);
    }
  const int leadingNodes = static_cast<int>(leading.size());
  std::vector<int> nodeOrder(leadingNodes);
  if (leadingNodes > 0) {
    std::vector<int> columnStart, rows;
    NodeGraphUpper(compact, leadingNodes, visitNeighbours, columnStart, rows);
    const char* method = "METIS";
    // No postorder here: CHOLMOD postorders the final DOF ordering in analyze.
    if (Status s = OrderGraph(leadingNodes, columnStart, rows,
                              ParallelDissectionDepth(leadingNodes, leaves), nodeOrder, method,
                              ordering.leaves);
        !s)
      return s;
    ordering.method = method;
  }

  ordering.permutation.clear();
  ordering.permutation.reserve(static_cast<size_t>(nodes) * dofsPerNode);
  auto appendNode = [&](int node) {
    for (int d = 0; d < dofsPerNode; ++d)
      ordering.permutation.push_back(node * dofsPerNode + d);
  };
  for (int k : nodeOrder)
    appendNode(leading[k]);
  for (int node = 0; node < nodes; ++node)
    if (isTrailing(node))
      appendNode(node);
  ordering.trailingDofs = (nodes - leadingNodes) * dofsPerNode;
  return Status::Ok();
}

} // namespace

Status OrderNodesWithTrailing(const SparseMatrix& upper, int dofsPerNode,
                              const std::vector<char>& trailingNode, FillReducingOrdering& ordering,
                              int leaves) {
  if (dofsPerNode <= 0 || upper.rows() % dofsPerNode != 0 || upper.rows() != upper.cols())
    return Status::Error("internal: ordering needs a square matrix of whole nodes");
  const int nodes = static_cast<int>(upper.rows() / dofsPerNode);
  return OrderWithTrailing(
      nodes, dofsPerNode, trailingNode,
      [&](int node, auto&& f) {
        for (int d = 0; d < dofsPerNode; ++d)
          for (SparseMatrix::InnerIterator it(upper, node * dofsPerNode + d); it; ++it)
            f(static_cast<int>(it.row() / dofsPerNode));
      },
      ordering, leaves);
}

Status OrderNodeGraphWithTrailing(const NodeNeighbours& lower, int nodes, int dofsPerNode,
                                  const std::vector<char>& trailingNode,
                                  FillReducingOrdering& ordering, int leaves) {
  if (dofsPerNode <= 0 || nodes < 0 || nodes > static_cast<int>(lower.size()))
    return Status::Error("internal: ordering needs whole nodes of the graph");
  return OrderWithTrailing(
      nodes, dofsPerNode, trailingNode,
      [&](int node, auto&& f) {
        for (int neighbour : lower[node])
          f(neighbour);
      },
      ordering, leaves);
}

std::vector<char> NodesCoupledToLaterNodes(const NodeNeighbours& lower, int nodes) {
  std::vector<char> coupled(nodes, 0);
  for (size_t later = static_cast<size_t>(nodes); later < lower.size(); ++later)
    for (int neighbour : lower[later])
      if (neighbour < nodes)
        coupled[neighbour] = 1;
  return coupled;
}

} // namespace faceplan
