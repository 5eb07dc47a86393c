// SPDX-License-Identifier: BSD-3-Clause
#include "Element/ElementStiffness.h"
#include "Element/StiffnessAssembly.h"
#include "Support/ShellMeshGenerator.h"

#include <Eigen/Dense>
#include <algorithm>
#include <gtest/gtest.h>
#include <numeric>

using namespace faceplan;

TEST(Assembly, GatherEqualsDenseElementSum) {
  const ShellMesh shell = MakeSphericalShell(2, 1, 1.0, 1.5);
  const TetMesh& mesh = shell.mesh;
  Materials mat;
  mat.youngsModulus = Eigen::VectorXd::LinSpaced(mesh.numTets(), 1.0, 7.0); // per-cell values
  mat.poissonRatio = Eigen::VectorXd::Constant(1, 0.3);
  std::vector<int> identity(mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0);
  AssemblyPattern pattern;

  ASSERT_TRUE(BuildAssemblyPattern(mesh, identity, static_cast<int>(mesh.numPoints()), pattern));
  PackedElementMatrices packed;
  ComputePackedElementStiffness(mesh, mat, packed);
  AssembleFromPacked(packed.data(), pattern);

  const Eigen::Index n = 3 * mesh.numPoints();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k)
      c.row(k) = mesh.points.row(mesh.tets(e, k));
    const ElementMatrix ke = TetStiffness(c, mat.E(e), mat.nu(e));
    for (int p = 0; p < 12; ++p)
      for (int q = 0; q < 12; ++q)
        dense(3 * mesh.tets(e, p / 3) + p % 3, 3 * mesh.tets(e, q / 3) + q % 3) += ke(p, q);
  }
  const SparseMatrix full = pattern.upper.selfadjointView<Eigen::Upper>();
  const Eigen::MatrixXd assembled = Eigen::MatrixXd(full);
  EXPECT_LT((assembled - dense).norm() / dense.norm(), 1e-14);
  // The pattern holds exactly the structurally non-zero upper entries.
  Eigen::Index structural = 0;
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i <= j; ++i)
      structural += dense(i, j) != 0.0;
  EXPECT_LE(structural, pattern.upper.nonZeros());
}

// Assembling only the cells that changed since a rest assembly gives the whole assembly's values:
// exactly where no changed cell reaches, to round-off elsewhere. A dropped node's entries have no
// place in the pattern, and then there is no map.
TEST(Assembly, ChangedCellsOnTopOfTheRestEqualTheWholeAssembly) {
  const ShellMesh shell = MakeSphericalShell(2, 2, 1.0, 1.5);
  const TetMesh& mesh = shell.mesh;
  std::vector<int> identity(mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0);
  AssemblyPattern pattern;
  ASSERT_TRUE(BuildAssemblyPattern(mesh, identity, static_cast<int>(mesh.numPoints()), pattern));
  const Eigen::Index m = mesh.numTets();
  PackedElementMatrices restCells, cells;
  ComputePackedElementStiffness(mesh, Materials::Uniform(3.0, 0.3), restCells);
  ComputePackedElementStiffness(mesh, Materials::Uniform(5.0, 0.45), cells);
  const std::vector<double> rest(restCells.begin(), restCells.end());
  std::vector<double> now = rest;
  std::vector<char> atRest(static_cast<size_t>(m), 1);
  for (Eigen::Index e = 0; e < m; e += 3) { // every third cell changed
    atRest[static_cast<size_t>(e)] = 0;
    std::copy_n(cells.data() + e * kPackedElementSize, kPackedElementSize,
                now.data() + e * kPackedElementSize);
  }
  AssembleFromPacked(rest.data(), pattern);
  const std::vector<double> restValues(pattern.upper.valuePtr(),
                                       pattern.upper.valuePtr() + pattern.upper.nonZeros());
  AssembleFromPacked(now.data(), pattern);
  const std::vector<double> whole(pattern.upper.valuePtr(),
                                  pattern.upper.valuePtr() + pattern.upper.nonZeros());
  const std::vector<int> entries = PackedEntries(pattern, rest.size());
  ASSERT_EQ(entries.size(), rest.size());
  std::vector<char> reached(whole.size(), 0);
  for (size_t k = 0; k < entries.size(); ++k)
    if (!atRest[k / kPackedElementSize])
      reached[static_cast<size_t>(entries[k])] = 1;
  pattern.upper.coeffs().setConstant(-1.0);
  AssembleChangedCells(restValues.data(), rest, now.data(), atRest, entries, pattern);
  const double largest =
      Eigen::Map<const Eigen::VectorXd>(whole.data(), whole.size()).cwiseAbs().maxCoeff();
  int exact = 0, close = 0;
  for (size_t k = 0; k < whole.size(); ++k) {
    const double v = pattern.upper.valuePtr()[k];
    if (reached[k]) {
      EXPECT_NEAR(v, whole[k], 1e-14 * largest) << k;
      ++close;
    } else {
      EXPECT_EQ(v, restValues[k]) << k;
      ++exact;
    }
  }
  EXPECT_GT(exact, 0);
  EXPECT_GT(close, 0);

  std::vector<int> dofNode(identity.size());
  for (size_t i = 0; i < dofNode.size(); ++i)
    dofNode[i] = static_cast<int>(i) - 1; // node 0 dropped
  AssemblyPattern dropped;
  ASSERT_TRUE(BuildAssemblyPattern(mesh, dofNode, static_cast<int>(mesh.numPoints()) - 1, dropped));
  EXPECT_TRUE(PackedEntries(dropped, rest.size()).empty());
}

TEST(Assembly, DroppedNodesHaveNoDofs) {
  const ShellMesh shell = MakeSphericalShell(2, 2, 1.0, 1.5);
  std::vector<int> dofNode(shell.mesh.numPoints(), -1);
  int next = 0;
  for (Eigen::Index i = shell.nodesPerLayer; i < shell.mesh.numPoints(); ++i)
    dofNode[i] = next++;
  AssemblyPattern pattern;

  ASSERT_TRUE(BuildAssemblyPattern(shell.mesh, dofNode, next, pattern));
  EXPECT_EQ(pattern.upper.rows(), 3 * next);
  EXPECT_EQ(pattern.upper.cols(), 3 * next);
}

// The gather map against its definition: every packed entry (p <= q) of every cell whose two nodes
// have DOFs contributes once to the upper entry of its (row, column) pair, and each entry lists its
// contributions in increasing packed index (the summation order, which fixes the round-off).
// Permuted DOF numbering with dropped nodes, so that rows and columns swap inside cells.
TEST(Assembly, GatherMapEqualsItsDefinition) {
  const ShellMesh shell = MakeSphericalShell(3, 2, 1.0, 1.5);
  const TetMesh& mesh = shell.mesh;
  const int points = static_cast<int>(mesh.numPoints());
  std::vector<int> dofNode(points, -1);
  int next = 0;
  for (int i = points - 1; i >= 0; --i) // reversed, every fifth node dropped
    if (i % 5 != 2)
      dofNode[i] = next++;
  AssemblyPattern pattern;
  ASSERT_TRUE(BuildAssemblyPattern(mesh, dofNode, next, pattern));

  const SparseMatrix& upper = pattern.upper;
  auto entryOf = [&](int row, int col) {
    for (SparseMatrix::InnerIterator it(upper, col); it; ++it)
      if (it.row() == row)
        return static_cast<int>(&it.value() - upper.valuePtr());
    return -1;
  };
  std::vector<std::vector<int>> expected(upper.nonZeros());
  int packed = 0;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int p = 0; p < 12; ++p)
      for (int q = p; q < 12; ++q, ++packed) {
        const int a = dofNode[mesh.tets(e, p / 3)], b = dofNode[mesh.tets(e, q / 3)];
        if (a < 0 || b < 0)
          continue;
        int row = 3 * a + p % 3, col = 3 * b + q % 3;
        if (row > col)
          std::swap(row, col);
        const int k = entryOf(row, col);
        ASSERT_GE(k, 0) << "cell " << e << " entry (" << row << ", " << col
                        << ") not in the pattern";
        expected[k].push_back(packed);
      }
  ASSERT_EQ(pattern.gatherStart.size(), static_cast<size_t>(upper.nonZeros()) + 1);
  for (Eigen::Index k = 0; k < upper.nonZeros(); ++k) {
    const std::vector<int> listed(pattern.packedIndex.begin() + pattern.gatherStart[k],
                                  pattern.packedIndex.begin() + pattern.gatherStart[k + 1]);
    ASSERT_EQ(listed, expected[k]) << "entry " << k;
  }
}

TEST(Assembly, RefusesACellWithARepeatedNode) {
  const ShellMesh shell = MakeSphericalShell(2, 1, 1.0, 1.5);
  TetMesh mesh = shell.mesh;
  mesh.tets(3, 2) = mesh.tets(3, 0);
  std::vector<int> identity(mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0);
  AssemblyPattern pattern;
  const Status s =
      BuildAssemblyPattern(mesh, identity, static_cast<int>(mesh.numPoints()), pattern);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("same node twice"), std::string::npos) << s.message;
}
