#include "SparseSolver/FillReducingOrdering.h"

#include "SparseSolver/CholmodViews.h"

#include <cholmod.h>
#include <string>

namespace faceplan {

namespace {

// Upper-triangular pattern (CSC, strictly above the diagonal) of the node graph of the nodes
// with compact index >= 0, numbered by that index.
void NodeGraphUpper(const SparseMatrix& upper, int dofsPerNode, const std::vector<int>& compact,
                    int compactNodes, std::vector<int>& columnStart, std::vector<int>& rows) {
  std::vector<int> lastSeen(compactNodes, -1);
  columnStart.assign(1, 0);
  rows.clear();
  const int nodes = static_cast<int>(compact.size());
  for (int node = 0; node < nodes; ++node) {
    const int column = compact[node];
    if (column < 0)
      continue;
    for (int d = 0; d < dofsPerNode; ++d)
      for (SparseMatrix::InnerIterator it(upper, node * dofsPerNode + d); it; ++it) {
        const int row = compact[it.row() / dofsPerNode];
        if (row < 0 || row >= column || lastSeen[row] == column)
          continue;
        lastSeen[row] = column;
        rows.push_back(row);
      }
    columnStart.push_back(static_cast<int>(rows.size()));
  }
}

} // namespace

std::vector<char> NodesCoupledTo(const SparseMatrix& coupling, int freeNodes, int dofsPerNode) {
  std::vector<char> coupled(freeNodes, 0);
  for (int c = 0; c < coupling.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(coupling, c); it; ++it)
      coupled[it.row() / dofsPerNode] = 1;
  return coupled;
}

Status OrderNodesWithTrailing(const SparseMatrix& upper, int dofsPerNode,
                              const std::vector<char>& trailingNode,
                              FillReducingOrdering& ordering) {
  if (dofsPerNode <= 0 || upper.rows() % dofsPerNode != 0 || upper.rows() != upper.cols())
    return Status::Error("internal: ordering needs a square matrix of whole nodes");
  const int nodes = static_cast<int>(upper.rows() / dofsPerNode);
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
    NodeGraphUpper(upper, dofsPerNode, compact, leadingNodes, columnStart, rows);
    QuietCholmodCommon quiet;
    cholmod_common& common = quiet.common;
    cholmod_sparse graph{};
    graph.nrow = graph.ncol = static_cast<size_t>(leadingNodes);
    graph.nzmax = rows.size();
    graph.p = columnStart.data();
    graph.i = rows.empty() ? nullptr : rows.data();
    graph.stype = 1;
    graph.itype = CHOLMOD_INT;
    graph.xtype = CHOLMOD_PATTERN;
    graph.dtype = CHOLMOD_DOUBLE;
    graph.sorted = 0;
    graph.packed = 1;
    std::vector<int> dummyRow(1, 0);
    if (rows.empty())
      graph.i = dummyRow.data(); // CHOLMOD wants a non-null array
    ordering.method = "METIS";
    // No postorder here: CHOLMOD postorders the final DOF ordering in analyze.
    int ok = cholmod_metis(&graph, nullptr, 0, 0, nodeOrder.data(), &common);
    if (!ok) {
      ordering.method = "AMD";
      common.status = CHOLMOD_OK;
      ok = cholmod_amd(&graph, nullptr, 0, nodeOrder.data(), &common);
    }
    if (!ok)
      return Status::Error("fill-reducing ordering failed (CHOLMOD status " +
                           std::to_string(common.status) + ")");
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

} // namespace faceplan
