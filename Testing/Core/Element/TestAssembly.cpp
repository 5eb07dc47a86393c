#include "Element/ElementStiffness.h"
#include "Support/ShellMeshGenerator.h"
#include "Element/StiffnessAssembly.h"

#include <Eigen/Dense>
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
  std::vector<double> packed;
  ComputePackedElementStiffness(mesh, mat, packed);
  AssembleFromPacked(packed, pattern);

  const Eigen::Index n = 3 * mesh.numPoints();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k) c.row(k) = mesh.points.row(mesh.tets(e, k));
    const ElementMatrix ke = TetStiffness(c, mat.E(e), mat.nu(e));
    for (int p = 0; p < 12; ++p)
      for (int q = 0; q < 12; ++q) dense(3 * mesh.tets(e, p / 3) + p % 3, 3 * mesh.tets(e, q / 3) + q % 3) += ke(p, q);
  }
  const SparseMatrix full = pattern.upper.selfadjointView<Eigen::Upper>();
  const Eigen::MatrixXd assembled = Eigen::MatrixXd(full);
  EXPECT_LT((assembled - dense).norm() / dense.norm(), 1e-14);
  // The pattern holds exactly the structurally non-zero upper entries.
  Eigen::Index structural = 0;
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i <= j; ++i) structural += dense(i, j) != 0.0;
  EXPECT_LE(structural, pattern.upper.nonZeros());
}

TEST(Assembly, DroppedNodesHaveNoDofs) {
  const ShellMesh shell = MakeSphericalShell(2, 2, 1.0, 1.5);
  std::vector<int> dofNode(shell.mesh.numPoints(), -1);
  int next = 0;
  for (Eigen::Index i = shell.nodesPerLayer; i < shell.mesh.numPoints(); ++i) dofNode[i] = next++;
  AssemblyPattern pattern;

  ASSERT_TRUE(BuildAssemblyPattern(shell.mesh, dofNode, next, pattern));
  EXPECT_EQ(pattern.upper.rows(), 3 * next);
  EXPECT_EQ(pattern.upper.cols(), 3 * next);
}
