#include "SparseSolver/FillReducingOrdering.h"

#include "SparseSolver/CholmodViews.h"


#include <algorithm>
#include <cholmod.h>
#include <string>
#include <mutex>

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
void NodeGraphUpper(const std::vector<int>& compact, int compactNodes, VisitNeighbours&& visitNeighbours,
                    std::vector<int>& columnStart, std::vector<int>& rows) {
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

// METIS nested dissection of a graph (CSC upper pattern), AMD when METIS fails. `method` names
// what ordered it.
Status OrderGraph(int n, std::vector<int>& columnStart, std::vector<int>& rows,
                  std::vector<int>& order, const char*& method) {
  order.resize(n);
  std::vector<int> dummyRow(1, 0);
  cholmod_sparse graph = ViewPattern(n, columnStart, rows, dummyRow);
  QuietCholmodCommon quiet;
  cholmod_common& common = quiet.common;
  method = "METIS";
  {
    std::lock_guard<std::mutex> metis(MetisMutex());
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
                         VisitNeighbours&& visitNeighbours, FillReducingOrdering& ordering) {
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
    if (Status s = OrderGraph(leadingNodes, columnStart, rows, nodeOrder, method); !s)
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
                              const std::vector<char>& trailingNode,
                              FillReducingOrdering& ordering) {
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
      ordering);
}

Status OrderNodeGraphWithTrailing(const NodeNeighbours& lower, int nodes, int dofsPerNode,
                                  const std::vector<char>& trailingNode,
                                  FillReducingOrdering& ordering) {
  if (dofsPerNode <= 0 || nodes < 0 || nodes > static_cast<int>(lower.size()))
    return Status::Error("internal: ordering needs whole nodes of the graph");
  return OrderWithTrailing(
      nodes, dofsPerNode, trailingNode,
      [&](int node, auto&& f) {
        for (int neighbour : lower[node])
          f(neighbour);
      },
      ordering);
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
