#include "Element/StiffnessAssembly.h"

#include "Element/ElementStiffness.h"
#include "Common/GroupByKey.h"
#include "Common/ParallelFor.h"

#include <algorithm>
#include <limits>

namespace faceplan {

void FinishGatherMap(const std::vector<int>& targetOf, AssemblyPattern& pattern) {
  Groups gather =
      GroupByKey(static_cast<std::int64_t>(targetOf.size()),
                 static_cast<int>(pattern.upper.nonZeros()), [&](std::int64_t idx) { return targetOf[idx]; });
  pattern.gatherStart = std::move(gather.start);
  pattern.packedIndex = std::move(gather.items);
}

NodeNeighbours LowerNodeNeighbours(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                   const std::vector<int>& dofNode, int numDofNodes) {
  // A node-to-cell index first (cell corners grouped by node), then the nodes in parallel, each
  // writing only its own list.
  const Groups cornersOf = GroupByKey(numCells * nodesPerCell, numDofNodes, [&](std::int64_t corner) {
    return dofNode[cells[corner]];
  });
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
  return BuildCellAssemblyPattern(
      cells, numCells, nodesPerCell, dofNode,
      LowerNodeNeighbours(cells, numCells, nodesPerCell, dofNode, numDofNodes), pattern);
}

Status BuildCellAssemblyPattern(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                const std::vector<int>& dofNode, const NodeNeighbours& lower,
                                AssemblyPattern& pattern) {
  pattern = AssemblyPattern{};
  const int dofs = 3 * nodesPerCell;
  const long long packedSize = static_cast<long long>(dofs) * (dofs + 1) / 2;
  if (numCells > std::numeric_limits<int>::max() / packedSize)
    return Status::Error("mesh too large for 32-bit packed indices");
  auto node = [&](Eigen::Index e, int k) { return cells[e * nodesPerCell + k]; };
  if (Status built = UpperPatternOfNodes(lower, static_cast<int>(lower.size()), true, pattern.upper);
      !built)
    return built;
  const int* colStart = pattern.upper.outerIndexPtr();

  std::vector<int> rowStart(dofs); // packed position of (p, p)
  for (int p = 0, pos = 0; p < dofs; ++p) {
    rowStart[p] = pos;
    pos += dofs - p;
  }
  std::vector<int> targetOf(static_cast<size_t>(numCells) * packedSize);
  ParallelFor(numCells, 20000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t e = begin; e < end; ++e)
      for (int p = 0; p < dofs; ++p)
        for (int q = p; q < dofs; ++q) {
          int nr = dofNode[node(e, p / 3)], nc = dofNode[node(e, q / 3)];
          int t = -1;
          if (nr >= 0 && nc >= 0) {
            int ir = p % 3, ic = q % 3;
            if (nr > nc || (nr == nc && ir > ic)) {
              std::swap(nr, nc);
              std::swap(ir, ic);
            }
            const auto& rows = lower[nc];
            const int idx =
                static_cast<int>(std::lower_bound(rows.begin(), rows.end(), nr) - rows.begin());
            t = colStart[3 * nc + ic] + 3 * idx + ir;
          }
          targetOf[e * packedSize + rowStart[p] + (q - p)] = t;
        }
  });
  FinishGatherMap(targetOf, pattern);
  return Status::Ok();
}

Status BuildAssemblyPattern(const TetMesh& mesh, const std::vector<int>& dofNode, int numDofNodes,
                            AssemblyPattern& pattern) {
  return BuildCellAssemblyPattern(mesh.tets.data(), mesh.numTets(), 4, dofNode, numDofNodes,
                                  pattern);
}

void AssembleFromPacked(const std::vector<double>& packed, AssemblyPattern& pattern) {
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

} // namespace faceplan
