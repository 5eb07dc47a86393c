#include "Element/StiffnessAssembly.h"

#include "Element/ElementStiffness.h"
#include "Common/ParallelFor.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace faceplan {

namespace {

// Position of (p, q), p <= q, in a row-by-row packed upper triangle of a 12x12 matrix.
int PackedPosition(int p, int q) { return p * 12 - p * (p - 1) / 2 + (q - p); }

} // namespace

void FinishGatherMap(const std::vector<int>& targetOf, AssemblyPattern& pattern) {
  const int nnz = static_cast<int>(pattern.upper.nonZeros());
  pattern.gatherStart.assign(nnz + 1, 0);
  for (const int t : targetOf)
    if (t >= 0) ++pattern.gatherStart[t + 1];
  for (int k = 0; k < nnz; ++k) pattern.gatherStart[k + 1] += pattern.gatherStart[k];
  pattern.packedIndex.resize(pattern.gatherStart[nnz]);
  std::vector<int> fill(pattern.gatherStart.begin(), pattern.gatherStart.end() - 1);
  for (size_t idx = 0; idx < targetOf.size(); ++idx) {
    const int t = targetOf[idx];
    if (t >= 0) pattern.packedIndex[fill[t]++] = static_cast<int>(idx);
  }
}

AssemblyPattern BuildAssemblyPattern(const TetMesh& mesh, const std::vector<int>& dofNode,
                                     int numDofNodes) {
  const Eigen::Index m = mesh.numTets();
  if (m > std::numeric_limits<int>::max() / kPackedElementSize)
    throw std::length_error("mesh too large for 32-bit packed indices");

  // Node-level upper pattern: for each column node c, the sorted row nodes r <= c.
  std::vector<std::vector<int>> rowsOf(numDofNodes);
  for (Eigen::Index e = 0; e < m; ++e) {
    for (int a = 0; a < 4; ++a) {
      const int na = dofNode[mesh.tets(e, a)];
      if (na < 0) continue;
      for (int b = 0; b < 4; ++b) {
        const int nb = dofNode[mesh.tets(e, b)];
        if (nb >= 0 && nb <= na) rowsOf[na].push_back(nb);
      }
    }
  }
  for (auto& rows : rowsOf) {
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  }

  // DOF-level CSC of the upper triangle.
  const int n = 3 * numDofNodes;
  std::vector<int> colStart(n + 1, 0);
  for (int c = 0; c < numDofNodes; ++c) {
    const int offDiagonal = 3 * static_cast<int>(rowsOf[c].size() - 1);
    for (int j = 0; j < 3; ++j) colStart[3 * c + j + 1] = colStart[3 * c + j] + offDiagonal + j + 1;
  }
  const int nnz = colStart[n];
  AssemblyPattern pattern;
  pattern.upper.resize(n, n);
  pattern.upper.resizeNonZeros(nnz);
  std::copy(colStart.begin(), colStart.end(), pattern.upper.outerIndexPtr());
  int* rowIndex = pattern.upper.innerIndexPtr();
  for (int c = 0; c < numDofNodes; ++c) {
    for (int j = 0; j < 3; ++j) {
      int k = colStart[3 * c + j];
      for (int r : rowsOf[c]) {
        const int components = (r == c) ? j + 1 : 3;
        for (int i = 0; i < components; ++i) rowIndex[k++] = 3 * r + i;
      }
    }
  }
  std::fill(pattern.upper.valuePtr(), pattern.upper.valuePtr() + nnz, 0.0);

  // Target nonzero of every packed element entry, then a counting sort into gather lists.
  auto target = [&](Eigen::Index e, int p, int q) -> int {
    int nr = dofNode[mesh.tets(e, p / 3)], nc = dofNode[mesh.tets(e, q / 3)];
    if (nr < 0 || nc < 0) return -1;
    int ir = p % 3, ic = q % 3;
    if (nr > nc || (nr == nc && ir > ic)) {
      std::swap(nr, nc);
      std::swap(ir, ic);
    }
    const auto& rows = rowsOf[nc];
    const int idx = static_cast<int>(std::lower_bound(rows.begin(), rows.end(), nr) - rows.begin());
    return colStart[3 * nc + ic] + 3 * idx + ir;
  };
  std::vector<int> targetOf(static_cast<size_t>(m) * kPackedElementSize);
  for (Eigen::Index e = 0; e < m; ++e) {
    for (int p = 0; p < 12; ++p) {
      for (int q = p; q < 12; ++q) {
        const int t = target(e, p, q);
        targetOf[e * kPackedElementSize + PackedPosition(p, q)] = t;
      }
    }
  }
  FinishGatherMap(targetOf, pattern);
  return pattern;
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
