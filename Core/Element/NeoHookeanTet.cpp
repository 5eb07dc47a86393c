// SPDX-License-Identifier: BSD-3-Clause
#include "Element/NeoHookeanTet.h"

#include <Eigen/LU>
#include <cmath>

namespace faceplan {

namespace {

// J^(-2/3), the isochoric factor, through cbrt: the innermost loop of the large-deformation
// solves calls it per cell and evaluation, and cbrt costs a fraction of pow.
double IsochoricFactor(double J) {
  const double c = std::cbrt(J);
  return 1.0 / (c * c);
}

} // namespace

NeoHookeanParameters NeoHookeanFromLinear(double E, double nu) {
  NeoHookeanParameters p;
  p.mu = E / (2.0 * (1.0 + nu));
  p.kappa = E / (3.0 * (1.0 - 2.0 * nu));
  return p;
}

TetReference MakeTetReference(const TetCorners& corners) {
  Eigen::Matrix3d edges; // columns X_j - X_0
  for (int j = 0; j < 3; ++j)
    edges.col(j) = (corners.row(j + 1) - corners.row(0)).transpose();
  const Eigen::Matrix3d inverse = edges.inverse();
  TetReference r;
  r.gradients.bottomRows<3>() = inverse; // row a - 1 of edges^-1 is grad N_a
  r.gradients.row(0) = -inverse.colwise().sum();
  r.volume = edges.determinant() / 6.0;
  return r;
}

Eigen::Matrix3d DeformationGradient(const TetReference& reference, const CornerDisplacements& u) {
  return Eigen::Matrix3d::Identity() + u.transpose() * reference.gradients;
}

double NeoHookeanEnergyDensity(const Eigen::Matrix3d& F, const NeoHookeanParameters& p) {
  const double J = F.determinant();
  return 0.5 * p.mu * (IsochoricFactor(J) * F.squaredNorm() - 3.0) +
         0.5 * p.kappa * (J - 1.0) * (J - 1.0);
}

Eigen::Matrix3d NeoHookeanStress(const Eigen::Matrix3d& F, const NeoHookeanParameters& p) {
  const double J = F.determinant();
  const Eigen::Matrix3d inverseT = F.inverse().transpose();
  const double a = IsochoricFactor(J), i1 = F.squaredNorm();
  return p.mu * a * (F - (i1 / 3.0) * inverseT) + p.kappa * (J - 1.0) * J * inverseT;
}

namespace {

// dP for a change dF of F (the derivative of NeoHookeanStress), written out so that the 9 x 9
// material tangent costs nine evaluations of a few 3 x 3 products.
struct StressDerivative {
  StressDerivative(const Eigen::Matrix3d& F, const NeoHookeanParameters& p) : F(F), p(p) {
    J = F.determinant();
    inverseT = F.inverse().transpose();
    a = IsochoricFactor(J);
    i1 = F.squaredNorm();
    deviator = F - (i1 / 3.0) * inverseT;
  }
  Eigen::Matrix3d operator()(const Eigen::Matrix3d& dF) const {
    const double dJOverJ = (inverseT.array() * dF.array()).sum(); // tr(F^-1 dF)
    const double dI1Half = (F.array() * dF.array()).sum();        // F : dF
    const Eigen::Matrix3d dInverseT = -inverseT * dF.transpose() * inverseT;
    const Eigen::Matrix3d isochoric = p.mu * a *
                                      (-(2.0 / 3.0) * dJOverJ * deviator + dF -
                                       (2.0 / 3.0) * dI1Half * inverseT - (i1 / 3.0) * dInverseT);
    const Eigen::Matrix3d volumetric =
        p.kappa * ((2.0 * J - 1.0) * J * dJOverJ * inverseT + (J * J - J) * dInverseT);
    return isochoric + volumetric;
  }
  const Eigen::Matrix3d& F;
  const NeoHookeanParameters& p;
  double J, a, i1;
  Eigen::Matrix3d inverseT, deviator;
};

} // namespace

bool NeoHookeanTetState(const TetReference& reference, const NeoHookeanParameters& p,
                        const CornerDisplacements& u, double& energy, ElementVector& force,
                        ElementMatrix* tangent) {
  const Eigen::Matrix3d F = DeformationGradient(reference, u);
  const double J = F.determinant();
  if (!(J > 0.0))
    return false;
  const Eigen::Matrix<double, 4, 3>& G = reference.gradients;
  const double V = reference.volume;
  // NeoHookeanEnergyDensity and NeoHookeanStress with their shared terms computed once (the same
  // expressions, so the same values): this is the large-deformation solve's innermost loop.
  const double a = IsochoricFactor(J), i1 = F.squaredNorm();
  energy = V * (0.5 * p.mu * (a * i1 - 3.0) + 0.5 * p.kappa * (J - 1.0) * (J - 1.0));
  const Eigen::Matrix3d inverseT = F.inverse().transpose();
  const Eigen::Matrix3d P =
      p.mu * a * (F - (i1 / 3.0) * inverseT) + p.kappa * (J - 1.0) * J * inverseT;
  // f_a = V P grad N_a.
  const Eigen::Matrix<double, 4, 3> f = V * G * P.transpose();
  for (int a = 0; a < 4; ++a)
    force.segment<3>(3 * a) = f.row(a).transpose();
  if (!tangent)
    return true;
  // dF for a unit change of DOF (b, k) is e_k (x) grad N_b; the tangent's column (b, k) is
  // V dP grad N_a for each row block a.
  const StressDerivative dP(F, p);
  for (int k = 0; k < 3; ++k) {
    // dP is linear in dF, so the column for corner b is sum_l G(b, l) dP(e_k e_l^T).
    Eigen::Matrix3d unit[3];
    for (int l = 0; l < 3; ++l) {
      Eigen::Matrix3d dF = Eigen::Matrix3d::Zero();
      dF(k, l) = 1.0;
      unit[l] = dP(dF);
    }
    for (int b = 0; b < 4; ++b) {
      const Eigen::Matrix3d dPb = G(b, 0) * unit[0] + G(b, 1) * unit[1] + G(b, 2) * unit[2];
      const Eigen::Matrix<double, 4, 3> column = V * G * dPb.transpose();
      for (int a = 0; a < 4; ++a)
        tangent->block<3, 1>(3 * a, 3 * b + k) = column.row(a).transpose();
    }
  }
  // Symmetric in exact arithmetic; symmetrised so the assembled upper triangle is the matrix.
  *tangent = 0.5 * (*tangent + tangent->transpose()).eval();
  return true;
}

bool SmallStrainTetState(const TetReference& reference, const NeoHookeanParameters& p,
                         const CornerDisplacements& u, double& energy, ElementVector& force,
                         ElementMatrix* tangent) {
  const Eigen::Matrix<double, 4, 3>& g = reference.gradients;
  const Eigen::Matrix3d H = u.transpose() * g; // H_ij = sum_a u_a,i dN_a/dX_j
  if (!((Eigen::Matrix3d::Identity() + H).determinant() > 0.0))
    return false;
  const Eigen::Matrix3d eps = 0.5 * (H + H.transpose());
  const double lambda = p.kappa - 2.0 * p.mu / 3.0, trace = eps.trace();
  const Eigen::Matrix3d sigma = 2.0 * p.mu * eps + lambda * trace * Eigen::Matrix3d::Identity();
  const double V = reference.volume;
  energy = V * (p.mu * eps.cwiseProduct(eps).sum() + 0.5 * lambda * trace * trace);
  for (int a = 0; a < 4; ++a)
    force.segment<3>(3 * a) = V * sigma * g.row(a).transpose();
  if (tangent) {
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const double dot = g.row(a).dot(g.row(b));
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            (*tangent)(3 * a + i, 3 * b + j) =
                V *
                (p.mu * ((i == j ? dot : 0.0) + g(a, j) * g(b, i)) + lambda * g(a, i) * g(b, j));
      }
  }
  return true;
}

} // namespace faceplan
