// SPDX-License-Identifier: BSD-3-Clause
#include "Element/ElementStiffness.h"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

using namespace faceplan;

namespace {

TetCorners SampleTet() {
  TetCorners c;
  c << 0.1, 0.2, -0.1, 1.3, 0.1, 0.2, 0.2, 1.1, 0.0, 0.3, 0.4, 0.9;
  return c;
}

// Independent textbook form: explicit 6x12 strain matrix B and 6x6 constitutive matrix D.
ElementMatrix TextbookStiffness(const TetCorners& c, double E, double nu) {
  Eigen::Matrix4d M;
  for (int a = 0; a < 4; ++a)
    M.row(a) << 1.0, c(a, 0), c(a, 1), c(a, 2);
  const Eigen::Matrix4d coeff = M.inverse(); // column a holds N_a's coefficients
  Eigen::Matrix<double, 6, 12> B = Eigen::Matrix<double, 6, 12>::Zero();
  for (int a = 0; a < 4; ++a) {
    const double bx = coeff(1, a), by = coeff(2, a), bz = coeff(3, a);
    B(0, 3 * a) = bx;
    B(1, 3 * a + 1) = by;
    B(2, 3 * a + 2) = bz;
    B(3, 3 * a) = by, B(3, 3 * a + 1) = bx;     // gamma_xy
    B(4, 3 * a + 1) = bz, B(4, 3 * a + 2) = by; // gamma_yz
    B(5, 3 * a) = bz, B(5, 3 * a + 2) = bx;     // gamma_xz
  }
  const double f = E / ((1 + nu) * (1 - 2 * nu));
  Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
  D.topLeftCorner<3, 3>().setConstant(f * nu);
  D.topLeftCorner<3, 3>().diagonal().setConstant(f * (1 - nu));
  D.bottomRightCorner<3, 3>().diagonal().setConstant(f * (1 - 2 * nu) / 2);
  return B.transpose() * D * B * std::abs(M.determinant()) / 6.0;
}

} // namespace

TEST(ElementStiffness, MatchesTextbookBtDB) {
  const TetCorners c = SampleTet();
  const ElementMatrix ke = TetStiffness(c, 1234.0, 0.37);
  const ElementMatrix ref = TextbookStiffness(c, 1234.0, 0.37);
  EXPECT_LT((ke - ref).norm() / ref.norm(), 1e-13);
}

TEST(ElementStiffness, SymmetricWithSixRigidModes) {
  const ElementMatrix ke = TetStiffness(SampleTet(), 10.0, 0.3);
  EXPECT_LT((ke - ke.transpose()).norm() / ke.norm(), 1e-14);
  Eigen::SelfAdjointEigenSolver<ElementMatrix> eig(ke);
  const auto& values = eig.eigenvalues();
  for (int k = 0; k < 6; ++k)
    EXPECT_LT(std::abs(values[k]), 1e-12 * values[11]);
  for (int k = 6; k < 12; ++k)
    EXPECT_GT(values[k], 1e-6 * values[11]);
}

TEST(ElementStiffness, VolumeSignAndScaling) {
  TetCorners c = SampleTet();
  const double v = TetVolume(c);
  EXPECT_GT(v, 0.0);
  // Stiffness of a linear element scales with length: K(2x) = 2 K(x).
  const ElementMatrix k1 = TetStiffness(c, 5.0, 0.25), k2 = TetStiffness(2.0 * c, 5.0, 0.25);
  EXPECT_LT((k2 - 2.0 * k1).norm() / k1.norm(), 1e-13);
  c.row(0).swap(c.row(1));
  EXPECT_LT(TetVolume(c), 0.0);
}
