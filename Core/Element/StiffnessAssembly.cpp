// SPDX-License-Identifier: BSD-3-Clause
#include "Element/StiffnessAssembly.h"

#include "Common/GroupByKey.h"
#include "Common/ParallelFor.h"
#include "Element/ElementStiffness.h"

#include <algorithm>
#include <limits>

namespace faceplan {

Groups CornersByNode(const int* cells, Eigen::Index numCells, int nodesPerCell,
                     const std::vector<int>& dofNode, int numDofNodes) {
  return GroupByKey(numCells * nodesPerCell, numDofNodes,
                    [&](std::int64_t corner) { return dofNode[cells[corner]]; });
}

NodeNeighbours LowerNodeNeighbours(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                   const std::vector<int>& dofNode, int numDofNodes) {
  return LowerNodeNeighbours(cells, nodesPerCell, dofNode,
                             CornersByNode(cells, numCells, nodesPerCell, dofNode, numDofNodes));
}

NodeNeighbours LowerNodeNeighbours(const int* cells, int nodesPerCell,
                                   const std::vector<int>& dofNode, const Groups& cornersOf) {
  // The nodes in parallel, each writing only its own list.
  const int numDofNodes = static_cast<int>(cornersOf.start.size()) - 1;
  NodeNeighbours lower(numDofNodes);
  ParallelFor(numDofNodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t na = begin; na < end; ++na) {
      std::vector<int>& rows = lower[na];
      for (int k = cornersOf.start[na]; k < cornersOf.start[na + 1]; ++k) {
        const int* cell = cells + (cornersOf.items[k] / nodesPerCell) * std::int64_t{nodesPerCell};
        for (int b = 0; b < nodesPerCell; ++b) {
          const int nb = dofNode[cell[b]];
          if (nb >= 0 && nb <= na)
            rows.push_back(nb);
        }
      }
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    }
  });
  return lower;
}

Status UpperPatternOfNodes(const NodeNeighbours& lower, int nodes, bool zeroValues,
                           SparseMatrix& upper) {
  const int n = 3 * nodes;
  std::vector<long long> colStart(static_cast<size_t>(n) + 1, 0);
  for (int c = 0; c < nodes; ++c) {
    const long long offDiagonal = 3LL * (static_cast<long long>(lower[c].size()) - 1);
    for (int j = 0; j < 3; ++j)
      colStart[3 * c + j + 1] = colStart[3 * c + j] + offDiagonal + j + 1;
  }
  if (colStart[n] > std::numeric_limits<int>::max())
    return Status::Error("stiffness matrix too large for 32-bit indices");
  const int nnz = static_cast<int>(colStart[n]);
  upper.resize(n, n);
  upper.resizeNonZeros(nnz);
  for (int k = 0; k <= n; ++k)
    upper.outerIndexPtr()[k] = static_cast<int>(colStart[k]);
  int* rowIndex = upper.innerIndexPtr();
  ParallelFor(nodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t c = begin; c < end; ++c)
      for (int j = 0; j < 3; ++j) {
        long long k = colStart[3 * c + j];
        for (int r : lower[c]) {
          const int components = (r == c) ? j + 1 : 3;
          for (int i = 0; i < components; ++i)
            rowIndex[k++] = 3 * r + i;
        }
      }
  });
  if (zeroValues)
    std::fill(upper.valuePtr(), upper.valuePtr() + nnz, 0.0);
  return Status::Ok();
}

Status BuildCellAssemblyPattern(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                const std::vector<int>& dofNode, int numDofNodes,
                                AssemblyPattern& pattern) {
  const Groups cornersOf = CornersByNode(cells, numCells, nodesPerCell, dofNode, numDofNodes);
  return BuildCellAssemblyPattern(cells, numCells, nodesPerCell, dofNode, cornersOf,
                                  LowerNodeNeighbours(cells, nodesPerCell, dofNode, cornersOf),
                                  pattern);
}

Status BuildCellAssemblyPattern(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                const std::vector<int>& dofNode, const Groups& cornersOf,
                                const NodeNeighbours& lower, AssemblyPattern& pattern) {
  pattern = AssemblyPattern{};
  const int dofs = 3 * nodesPerCell;
  const long long packedSize = static_cast<long long>(dofs) * (dofs + 1) / 2;
  if (numCells > std::numeric_limits<int>::max() / packedSize)
    return Status::Error("mesh too large for 32-bit packed indices");
  const int nodes = static_cast<int>(lower.size());
  if (Status built = UpperPatternOfNodes(lower, nodes, true, pattern.upper); !built)
    return built;
  const int* colStart = pattern.upper.outerIndexPtr();
  const int nnz = static_cast<int>(pattern.upper.nonZeros());

  std::vector<int> rowStart(dofs); // packed position of (p, p)
  for (int p = 0, pos = 0; p < dofs; ++p) {
    rowStart[p] = pos;
    pos += dofs - p;
  }
  auto packedPosition = [&](int p, int q) {
    return p <= q ? rowStart[p] + (q - p) : rowStart[q] + (p - q);
  };
  // The gather map column node by column node, in parallel: each node's three columns take the
  // contributions of the cells at that node (in increasing cell order, so each entry lists its
  // packed indices in increasing order), one per cell and entry. No cells x 78 intermediate and
  // no serial grouping of it: on the largest meshes those were a large serial part of the
  // precompute.
  if (static_cast<int>(cornersOf.start.size()) != nodes + 1)
    return Status::Error("internal: the corner index does not match the node graph");
  // visit(nc, t, packed): every contribution to the columns of node nc, t its entry in `upper`.
  auto visitNode = [&](int nc, auto&& visit) -> bool {
    const std::vector<int>& rows = lower[nc];
    for (int k = cornersOf.start[nc]; k < cornersOf.start[nc + 1]; ++k) {
      const std::int64_t corner = cornersOf.items[k];
      const std::int64_t cell = corner / nodesPerCell;
      const int b = static_cast<int>(corner % nodesPerCell); // nc's place in the cell
      const int* cellNodes = cells + cell * nodesPerCell;
      for (int a = 0; a < nodesPerCell; ++a) {
        const int nr = dofNode[cellNodes[a]];
        if (nr < 0 || nr > nc)
          continue;
        if (nr == nc && a != b)
          return false; // a node twice in one cell
        const int idx =
            static_cast<int>(std::lower_bound(rows.begin(), rows.end(), nr) - rows.begin());
        for (int ic = 0; ic < 3; ++ic)
          for (int ir = 0; ir < (nr == nc ? ic + 1 : 3); ++ir)
            visit(colStart[3 * nc + ic] + 3 * idx + ir,
                  static_cast<int>(cell * packedSize + packedPosition(3 * a + ir, 3 * b + ic)));
      }
    }
    return true;
  };
  std::vector<int> count(static_cast<size_t>(nnz) + 1, 0);
  std::vector<char> repeated(nodes, 0);
  ParallelFor(nodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t nc = begin; nc < end; ++nc)
      repeated[nc] = !visitNode(static_cast<int>(nc), [&](int t, int) { ++count[t + 1]; });
  });
  if (std::find(repeated.begin(), repeated.end(), 1) != repeated.end())
    return Status::Error("a cell names the same node twice");
  for (int t = 0; t < nnz; ++t) // no overflow: at most packedSize per cell, checked above
    count[t + 1] += count[t];
  pattern.packedIndex.resize(count[nnz]);
  ParallelFor(nodes, 20000, [&](std::int64_t begin, std::int64_t end) {
    if (begin >= end)
      return;
    // This thread's nodes own the entries [colStart[3 begin], colStart[3 end]).
    const int first = colStart[3 * begin], last = colStart[3 * end];
    std::vector<int> fill(count.begin() + first, count.begin() + last);
    for (std::int64_t nc = begin; nc < end; ++nc)
      visitNode(static_cast<int>(nc),
                [&](int t, int packed) { pattern.packedIndex[fill[t - first]++] = packed; });
  });
  pattern.gatherStart = std::move(count);
  return Status::Ok();
}

Status BuildAssemblyPattern(const TetMesh& mesh, const std::vector<int>& dofNode, int numDofNodes,
                            AssemblyPattern& pattern) {
  return BuildCellAssemblyPattern(mesh.tets.data(), mesh.numTets(), 4, dofNode, numDofNodes,
                                  pattern);
}

void AssembleFromPacked(const double* packed, AssemblyPattern& pattern) {
  const int nnz = static_cast<int>(pattern.upper.nonZeros());
  double* values = pattern.upper.valuePtr();
  ParallelFor(nnz, 200000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t k = begin; k < end; ++k) {
      double sum = 0.0;
      for (int g = pattern.gatherStart[k]; g < pattern.gatherStart[k + 1]; ++g)
        sum += packed[pattern.packedIndex[g]];
      values[k] = sum;
    }
  });
}

std::vector<int> PackedEntries(const AssemblyPattern& pattern, size_t packedSize) {
  std::vector<int> entries(packedSize, -1);
  for (size_t k = 0; k + 1 < pattern.gatherStart.size(); ++k)
    for (int g = pattern.gatherStart[k]; g < pattern.gatherStart[k + 1]; ++g)
      if (static_cast<size_t>(pattern.packedIndex[g]) < packedSize)
        entries[static_cast<size_t>(pattern.packedIndex[g])] = static_cast<int>(k);
  if (std::find(entries.begin(), entries.end(), -1) != entries.end())
    entries.clear();
  return entries;
}

void AssembleChangedCells(const double* restValues, const std::vector<double>& restPacked,
                          const double* packed, const std::vector<char>& atRest,
                          const std::vector<int>& entries, AssemblyPattern& pattern) {
  const std::int64_t nnz = pattern.upper.nonZeros();
  const std::int64_t parts = std::min<std::int64_t>(WorkerThreads(16), 8);
  double* values = pattern.upper.valuePtr();
  const double* rest = restPacked.data();
  const int* entry = entries.data();
  ParallelFor(parts, 2, [&](std::int64_t firstPart, std::int64_t lastPart) {
    for (std::int64_t part = firstPart; part < lastPart; ++part) {
      const int from = static_cast<int>(nnz * part / parts);
      const int to = static_cast<int>(nnz * (part + 1) / parts);
      std::copy(restValues + from, restValues + to, values + from);
      const unsigned span = static_cast<unsigned>(to - from);
      double elsewhere = 0.0; // where the entries of the other parts go
      for (size_t c = 0; c < atRest.size(); ++c) {
        if (atRest[c])
          continue;
        const size_t at = c * kPackedElementSize;
        for (size_t k = at; k < at + kPackedElementSize; ++k) {
          // A select, not a branch: a cell's entries fall in either part without a pattern.
          const bool mine = static_cast<unsigned>(entry[k] - from) < span;
          double* target = mine ? values + entry[k] : &elsewhere;
          *target += packed[k] - rest[k];
        }
      }
    }
  });
}

} // namespace faceplan
