// SPDX-License-Identifier: BSD-3-Clause
// The neo-Hookean cell: its force is the energy's gradient, its tangent the force's derivative,
// its small-strain limit the linear element, and a rigid rotation costs nothing.
#include "Element/ElementStiffness.h"
#include "Element/NeoHookeanTet.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>

using namespace faceplan;

namespace {

TetCorners SkewedTet() {
  TetCorners c;
  c << 0.1, 0.2, -0.3, 2.3, 0.4, 0.1, 0.6, 1.9, 0.2, 0.5, 0.7, 2.1;
  return c;
}

// A deformation of tens of percent, with shear and volume change.
CornerDisplacements LargeMove(const TetCorners& corners) {
  Eigen::Matrix3d grad;
  grad << 0.35, -0.2, 0.1, 0.15, -0.25, 0.3, -0.1, 0.2, 0.4;
  CornerDisplacements u = (corners * grad.transpose()).eval();
  u.row(2) += Eigen::RowVector3d(0.05, -0.03, 0.02);
  return u;
}

const NeoHookeanParameters kTissue = NeoHookeanFromLinear(3000.0, 0.45);

TEST(NeoHookeanTet, ForceIsTheEnergyGradient) {
  const TetReference ref = MakeTetReference(SkewedTet());
  const CornerDisplacements u = LargeMove(SkewedTet());
  double energy;
  ElementVector force;
  ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, u, energy, force, nullptr));
  const double h = 1e-6;
  for (int dof = 0; dof < 12; ++dof) {
    CornerDisplacements plus = u, minus = u;
    plus(dof / 3, dof % 3) += h;
    minus(dof / 3, dof % 3) -= h;
    double ep, em;
    ElementVector unused;
    ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, plus, ep, unused, nullptr));
    ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, minus, em, unused, nullptr));
    EXPECT_NEAR((ep - em) / (2 * h), force[dof], 1e-6 * force.cwiseAbs().maxCoeff()) << dof;
  }
}

TEST(NeoHookeanTet, TangentIsTheForceDerivative) {
  const TetReference ref = MakeTetReference(SkewedTet());
  const CornerDisplacements u = LargeMove(SkewedTet());
  double energy;
  ElementVector force;
  ElementMatrix tangent;
  ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, u, energy, force, &tangent));
  const double h = 1e-6;
  ElementMatrix difference;
  for (int dof = 0; dof < 12; ++dof) {
    CornerDisplacements plus = u, minus = u;
    plus(dof / 3, dof % 3) += h;
    minus(dof / 3, dof % 3) -= h;
    double e;
    ElementVector fp, fm;
    ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, plus, e, fp, nullptr));
    ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, minus, e, fm, nullptr));
    difference.col(dof) = (fp - fm) / (2 * h);
  }
  EXPECT_LT((difference - tangent).cwiseAbs().maxCoeff(), 1e-6 * tangent.cwiseAbs().maxCoeff());
  EXPECT_LT((tangent - tangent.transpose()).cwiseAbs().maxCoeff(),
            1e-12 * tangent.cwiseAbs().maxCoeff());
}

TEST(NeoHookeanTet, SmallStrainLimitIsTheLinearElement) {
  const TetCorners corners = SkewedTet();
  const TetReference ref = MakeTetReference(corners);
  double energy;
  ElementVector force;
  ElementMatrix tangent;
  ASSERT_TRUE(
      NeoHookeanTetState(ref, kTissue, CornerDisplacements::Zero(), energy, force, &tangent));
  const ElementMatrix linear = TetStiffness(corners, 3000.0, 0.45);
  EXPECT_LT((tangent - linear).cwiseAbs().maxCoeff(), 1e-12 * linear.cwiseAbs().maxCoeff());
  EXPECT_EQ(force.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NEAR(energy, 0.0, 1e-12);
}

TEST(NeoHookeanTet, RigidRotationCostsNothing) {
  const TetCorners corners = SkewedTet();
  const TetReference ref = MakeTetReference(corners);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.2, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  const CornerDisplacements u = (corners * (R - Eigen::Matrix3d::Identity()).transpose()).eval();
  double energy;
  ElementVector force;
  ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, u, energy, force, nullptr));
  // Against the force of a 1 % stretch: a linear element would see a 60 % "strain" here.
  double e1;
  ElementVector stretchForce;
  CornerDisplacements stretch = CornerDisplacements::Zero();
  stretch.col(0) = 0.01 * corners.col(0);
  ASSERT_TRUE(NeoHookeanTetState(ref, kTissue, stretch, e1, stretchForce, nullptr));
  EXPECT_LT(force.cwiseAbs().maxCoeff(), 1e-10 * stretchForce.cwiseAbs().maxCoeff());
  EXPECT_LT(std::abs(energy), 1e-10 * e1);
}

TEST(NeoHookeanTet, InvertedCellIsRejected) {
  const TetCorners corners = SkewedTet();
  const TetReference ref = MakeTetReference(corners);
  CornerDisplacements u = CornerDisplacements::Zero();
  u.row(3) = 2.0 * (corners.row(0) - corners.row(3)); // corner 3 pushed through the opposite face
  double energy = -1.0;
  ElementVector force;
  EXPECT_FALSE(NeoHookeanTetState(ref, kTissue, u, energy, force, nullptr));
  EXPECT_EQ(energy, -1.0);
}

// Four different cells, moves and materials, lane l holding cell l: `corner(l)` is the corner
// shifted from SkewedTet's, `shift(l)` its shift, `scale(l)` the LargeMove's scale and
// `material(l)` the lane's material.
struct FourCells {
  NeoHookeanTetLanes lanes;
  TetReference refs[kTetLanes];
  CornerDisplacements moves[kTetLanes];
  NeoHookeanParameters materials[kTetLanes];

  template <class Corner, class Shift, class Scale, class Material>
  FourCells(Corner corner, Shift shift, Scale scale, Material material) {
    for (int l = 0; l < kTetLanes; ++l) {
      TetCorners corners = SkewedTet();
      corners.row(corner(l)) += shift(l);
      refs[l] = MakeTetReference(corners);
      moves[l] = scale(l) * LargeMove(corners);
      materials[l] = material(l);
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) {
          lanes.corner[a][i][l] = moves[l](a, i);
          lanes.gradient[a][i][l] = refs[l].gradients(a, i);
        }
      lanes.volume[l] = refs[l].volume;
      lanes.mu[l] = materials[l].mu;
      lanes.kappa[l] = materials[l].kappa;
    }
  }
};

// The four-lane force kernel against the one-cell state, lane by lane, with each lane a different
// cell, move and material; and one inverted lane refuses the whole batch.
TEST(NeoHookeanTet, FourLaneForcesEqualTheCellState) {
  FourCells cells([](int l) { return l; },
                  [](int l) { return Eigen::RowVector3d(0.1 * l, -0.05 * l, 0.2); },
                  [](int l) { return 0.25 * (l + 1); },
                  [](int l) { return NeoHookeanFromLinear(1000.0 * (l + 1), 0.3 + 0.05 * l); });
  NeoHookeanTetLanes& lanes = cells.lanes;
  const TetReference* refs = cells.refs;
  const CornerDisplacements* moves = cells.moves;
  const NeoHookeanParameters* materials = cells.materials;
  ASSERT_TRUE(NeoHookeanTetForces(lanes));
  for (int l = 0; l < kTetLanes; ++l) {
    double energy;
    ElementVector force;
    ASSERT_TRUE(NeoHookeanTetState(refs[l], materials[l], moves[l], energy, force, nullptr));
    EXPECT_NEAR(lanes.energy[l], energy, 1e-13 * std::max(1.0, std::abs(energy))) << l;
    const double scale = std::max(force.cwiseAbs().maxCoeff(), 1e-300);
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(lanes.force[a][i][l], force[3 * a + i], 1e-13 * scale) << l << " " << a << i;
  }
  // At rest the stress, and so every force, is exactly zero (the CUDA backend's kernel gives
  // exactly zero there too, and its forces are compared with these relative to their size).
  NeoHookeanTetLanes rest = lanes;
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i)
      for (int l = 0; l < kTetLanes; ++l)
        rest.corner[a][i][l] = 0.0;
  ASSERT_TRUE(NeoHookeanTetForces(rest));
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i)
      for (int l = 0; l < kTetLanes; ++l)
        EXPECT_EQ(rest.force[a][i][l], 0.0) << l << " " << a << i;
  double restEnergy;
  ElementVector restForce;
  ASSERT_TRUE(NeoHookeanTetState(refs[0], materials[0], CornerDisplacements::Zero(), restEnergy,
                                 restForce, nullptr));
  EXPECT_EQ(restForce.cwiseAbs().maxCoeff(), 0.0);
  // Corner 3 of lane 2 pushed through the opposite face.
  const TetCorners corners = SkewedTet();
  for (int i = 0; i < 3; ++i)
    lanes.corner[3][i][2] = 2.0 * (corners(0, i) - corners(3, i));
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < 3; ++i)
      lanes.corner[a][i][2] = 0.0;
  EXPECT_FALSE(NeoHookeanTetForces(lanes));
}

// The four-lane tangents against the one-cell state's, lane by lane (packed upper triangle, row
// by row), with the forces the same as the force kernel's.
TEST(NeoHookeanTet, FourLaneTangentsEqualTheCellState) {
  FourCells cells([](int l) { return (l + 1) % 4; },
                  [](int l) { return Eigen::RowVector3d(-0.1 * l, 0.05 * l, 0.15); },
                  [](int l) { return 0.3 * (l + 1); },
                  [](int l) { return NeoHookeanFromLinear(800.0 * (l + 1), 0.45 - 0.05 * l); });
  NeoHookeanTetLanes& lanes = cells.lanes;
  const TetReference* refs = cells.refs;
  const CornerDisplacements* moves = cells.moves;
  const NeoHookeanParameters* materials = cells.materials;
  NeoHookeanTetLanes forcesOnly = lanes;
  ASSERT_TRUE(NeoHookeanTetForces(forcesOnly));
  double tangents[kPackedElementSize][kTetLanes];
  ASSERT_TRUE(NeoHookeanTetForcesAndTangents(lanes, tangents));
  for (int l = 0; l < kTetLanes; ++l) {
    double energy;
    ElementVector force;
    ElementMatrix tangent;
    ASSERT_TRUE(NeoHookeanTetState(refs[l], materials[l], moves[l], energy, force, &tangent));
    EXPECT_EQ(lanes.energy[l], forcesOnly.energy[l]) << l;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        EXPECT_EQ(lanes.force[a][i][l], forcesOnly.force[a][i][l]) << l << " " << a << i;
    const double scale = tangent.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    int entry = 0;
    for (int p = 0; p < 12; ++p)
      for (int q = p; q < 12; ++q, ++entry)
        EXPECT_NEAR(tangents[entry][l], tangent(p, q), 1e-13 * scale) << l << " " << p << q;
  }
  // An inverted lane refuses the batch.
  const TetCorners corners = SkewedTet();
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i)
      lanes.corner[a][i][1] = a == 3 ? 2.0 * (corners(0, i) - corners(3, i)) : 0.0;
  EXPECT_FALSE(NeoHookeanTetForcesAndTangents(lanes, tangents));
}

} // namespace
