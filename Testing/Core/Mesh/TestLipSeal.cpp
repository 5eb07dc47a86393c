// SPDX-License-Identifier: BSD-3-Clause
// LipSeal on two blocks facing each other across a gap (a lower and an upper lip): the bridges
// join exactly the facing surfaces, add no node, are positively oriented and carry the stiffened
// material; a solve moves the held block only when the seal ties it to the moved one.
#include "CondensedFEM/CondensedFEM.h"
#include "Mesh/LipSeal.h"
#include "Support/BoxMeshGenerator.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace faceplan {
namespace {

constexpr double kGap = 0.5;

// Two 4 x 4 x 1 blocks of 0.5 x 0.5 x 0.5 cells: the lower one on z in [0, 1], the upper one on
// z in [1 + kGap, 2 + kGap].
TetMesh TwoBlocks() {
  const TetMesh block = MakeBoxTetMesh(8, 8, 2, 4.0, 4.0, 1.0);
  TetMesh mesh;
  const Eigen::Index n = block.numPoints(), m = block.numTets();
  mesh.points.resize(2 * n, 3);
  mesh.tets.resize(2 * m, 4);
  mesh.points.topRows(n) = block.points;
  mesh.points.bottomRows(n) = block.points;
  mesh.points.bottomRows(n).col(2).array() += 1.0 + kGap;
  mesh.tets.topRows(m) = block.tets;
  mesh.tets.bottomRows(m) = block.tets.array() + static_cast<int>(n);
  return mesh;
}

double Volume(const TetMesh& mesh, Eigen::Index c) {
  const Eigen::Vector3d x0 = mesh.points.row(mesh.tets(c, 0));
  const Eigen::Vector3d x1 = mesh.points.row(mesh.tets(c, 1));
  const Eigen::Vector3d x2 = mesh.points.row(mesh.tets(c, 2));
  const Eigen::Vector3d x3 = mesh.points.row(mesh.tets(c, 3));
  return (x1 - x0).cross(x2 - x0).dot(x3 - x0) / 6.0;
}

TEST(LipSeal, BridgesJoinOnlyTheFacingSurfaces) {
  const TetMesh mesh = TwoBlocks();
  const Materials materials = Materials::Uniform(10.0, 0.3, 2.0);
  LipSealOptions options;
  options.gap = 2.0 * kGap;
  TetMesh sealed;
  Materials sealedMaterials;
  LipSealInfo info;
  ASSERT_TRUE(AddLipSeal(mesh, materials, options, sealed, sealedMaterials, info));
  EXPECT_EQ(sealed.numPoints(), mesh.numPoints());
  ASSERT_GT(info.bridges, 0);
  EXPECT_EQ(sealed.numTets(), mesh.numTets() + info.bridges);
  EXPECT_EQ(sealed.tets.topRows(mesh.numTets()), mesh.tets);
  // Every node of the two facing surfaces (81 each) is tied, and nothing else.
  EXPECT_EQ(info.tiedNodes, 2 * 81);
  ASSERT_EQ(sealedMaterials.youngsModulus.size(), sealed.numTets());
  for (Eigen::Index c = mesh.numTets(); c < sealed.numTets(); ++c) {
    EXPECT_GT(Volume(sealed, c), 0.0) << "bridge " << c;
    bool below = false, above = false;
    for (int k = 0; k < 4; ++k) {
      const double z = sealed.points(sealed.tets(c, k), 2);
      below = below || std::abs(z - 1.0) < 1e-12;
      above = above || std::abs(z - (1.0 + kGap)) < 1e-12;
      EXPECT_TRUE(std::abs(z - 1.0) < 1e-12 || std::abs(z - (1.0 + kGap)) < 1e-12)
          << "bridge " << c << " reaches beyond the facing surfaces";
    }
    EXPECT_TRUE(below && above) << "bridge " << c << " does not cross the gap";
    EXPECT_DOUBLE_EQ(sealedMaterials.youngsModulus[c], 10.0 * options.stiffnessFactor);
    EXPECT_DOUBLE_EQ(sealedMaterials.poissonRatio[c], 0.3);
    EXPECT_DOUBLE_EQ(sealedMaterials.density[c], 0.0);
  }
  EXPECT_DOUBLE_EQ(sealedMaterials.youngsModulus[0], 10.0);
  EXPECT_DOUBLE_EQ(sealedMaterials.density[0], 2.0);
  // The bridges, and only they, are small-strain cells for the large-deformation model.
  ASSERT_EQ(sealedMaterials.smallStrain.size(), static_cast<size_t>(sealed.numTets()));
  for (Eigen::Index c = 0; c < sealed.numTets(); ++c)
    EXPECT_EQ(sealedMaterials.isSmallStrain(c), c >= mesh.numTets()) << "cell " << c;
}

TEST(LipSeal, NothingBeyondTheGap) {
  const TetMesh mesh = TwoBlocks();
  LipSealOptions options;
  options.gap = 0.9 * kGap;
  TetMesh sealed;
  Materials sealedMaterials;
  LipSealInfo info;
  ASSERT_TRUE(
      AddLipSeal(mesh, Materials::Uniform(10.0, 0.3), options, sealed, sealedMaterials, info));
  EXPECT_EQ(info.bridges, 0);
  EXPECT_EQ(sealed.tets, mesh.tets);
  options.gap = 0.0;
  ASSERT_TRUE(
      AddLipSeal(mesh, Materials::Uniform(10.0, 0.3), options, sealed, sealedMaterials, info));
  EXPECT_EQ(info.bridges, 0);
}

TEST(LipSeal, BadInput) {
  const TetMesh mesh = TwoBlocks();
  TetMesh sealed;
  Materials sealedMaterials;
  LipSealInfo info;
  for (double gap :
       {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    LipSealOptions options;
    options.gap = gap;
    const Status status =
        AddLipSeal(mesh, Materials::Uniform(10.0, 0.3), options, sealed, sealedMaterials, info);
    EXPECT_FALSE(status);
    EXPECT_NE(status.message.find("gap"), std::string::npos) << status.message;
  }
  LipSealOptions options;
  options.gap = kGap;
  options.stiffnessFactor = 0.0;
  EXPECT_FALSE(
      AddLipSeal(mesh, Materials::Uniform(10.0, 0.3), options, sealed, sealedMaterials, info));
  Materials wrong;
  wrong.youngsModulus = Eigen::VectorXd::Constant(3, 10.0);
  wrong.poissonRatio = Eigen::VectorXd::Constant(1, 0.3);
  options.stiffnessFactor = 1000.0;
  EXPECT_FALSE(AddLipSeal(mesh, wrong, options, sealed, sealedMaterials, info));
}

// The lower block's bottom moves sideways, the upper block's top stays: unsealed, the upper block
// does not move at all; sealed, the lower block's top is held back and drags the upper block's
// bottom along, the two facing surfaces moving together.
TEST(LipSeal, TheHeldBlockRestrainsTheMovedOne) {
  const TetMesh mesh = TwoBlocks();
  const Materials materials = Materials::Uniform(10.0, 0.45);
  NodeSets sets;
  for (Eigen::Index i = 0; i < mesh.numPoints(); ++i) {
    const double z = mesh.points(i, 2);
    if (z < 1e-12)
      sets.movable.push_back(static_cast<int>(i));
    if (z < 1e-12 || z > 2.0 + kGap - 1e-12)
      sets.constrained.push_back(static_cast<int>(i));
    sets.kept.push_back(static_cast<int>(i));
  }
  auto solve = [&](double gap) {
    PrecomputeRequest request;
    LipSealInfo info;
    LipSealOptions options;
    options.gap = gap;
    EXPECT_TRUE(AddLipSeal(mesh, materials, options, request.mesh, request.materials, info));
    request.sets = sets;
    std::shared_ptr<const CondensedSystem> system;
    const Status pre = Precompute(request, system);
    EXPECT_TRUE(pre) << pre.message;
    SolveInput input;
    input.movableDisplacement = RowVectors3d::Zero(sets.movable.size(), 3);
    input.movableDisplacement.col(0).setConstant(0.1);
    SolveResult result;
    const Status s = Solve(*system, input, result);
    EXPECT_TRUE(s) << s.message;
    return result.keptDisplacement;
  };
  auto meanX = [&](const RowVectors3d& u, double z) {
    double sum = 0.0;
    int count = 0;
    for (Eigen::Index i = 0; i < mesh.numPoints(); ++i)
      if (std::abs(mesh.points(i, 2) - z) < 1e-12) {
        sum += u(i, 0);
        ++count;
      }
    return sum / count;
  };
  const RowVectors3d open = solve(0.0), closed = solve(2.0 * kGap);
  EXPECT_NEAR(meanX(open, 1.0), 0.1, 1e-9);         // the moved block follows its bone rigidly
  EXPECT_NEAR(meanX(open, 1.0 + kGap), 0.0, 1e-12); // the held block does not move
  EXPECT_LT(meanX(closed, 1.0), 0.09);              // held back by the sealed upper block
  EXPECT_GT(meanX(closed, 1.0 + kGap), 0.01);       // dragged along by the lower one
  // Welded: a penalty weld, so the facing surfaces move together to within a few per cent of the
  // move (the bridges are 1000 times as stiff as the tissue, not rigid).
  EXPECT_NEAR(meanX(closed, 1.0), meanX(closed, 1.0 + kGap), 0.05 * 0.1);
}

} // namespace
} // namespace faceplan
