// SPDX-License-Identifier: BSD-3-Clause
#include "Element/NeoHookeanTet.h"

#include <Eigen/LU>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace faceplan {

namespace {

// J^(-2/3), the isochoric factor: the innermost loop of the large-deformation solves calls it per
// cell and evaluation. y = J^(-1/3) by Newton's method, y <- y (4 - J y^3) / 3, from an estimate
// read off J's exponent bits (within a few per cent), then J^(-2/3) = y^2: four steps reach
// round-off (within 1e-15 of the exact value over J in [1e-3, 1e3], as close as 1 / cbrt(J)^2),
// in half the time of libm's cbrt and a division. Outside the range where the estimate holds
// (a cell nearly flat or blown up a hundredfold) cbrt does it.
double IsochoricFactor(double J) {
  if (!(J > 1e-100 && J < 1e100)) {
    const double c = std::cbrt(J);
    return 1.0 / (c * c);
  }
  std::uint64_t bits;
  std::memcpy(&bits, &J, sizeof bits);
  bits = 0x553EF0FF289DD796ull - bits / 3;
  double y;
  std::memcpy(&y, &bits, sizeof y);
  for (int step = 0; step < 4; ++step)
    y = y * (4.0 - J * y * y * y) * (1.0 / 3.0);
  return y * y;
}

// cof(F) = det(F) F^-T, written out: F^-T without the division and the second determinant that a
// general inverse computes, and det F = F's first row . cof's first row. F(i, j) reads an entry and
// c(i, j) is assigned one: a 3 x 3 matrix, or one lane of NeoHookeanTetForces' arrays.
// Always inlined: inside NeoHookeanTetForces' lane loop it must vectorize with its caller.
template <class In, class Out>
[[gnu::always_inline]] inline void WriteCofactor(const In& F, Out&& c) {
  c(0, 0) = F(1, 1) * F(2, 2) - F(1, 2) * F(2, 1);
  c(0, 1) = F(1, 2) * F(2, 0) - F(1, 0) * F(2, 2);
  c(0, 2) = F(1, 0) * F(2, 1) - F(1, 1) * F(2, 0);
  c(1, 0) = F(0, 2) * F(2, 1) - F(0, 1) * F(2, 2);
  c(1, 1) = F(0, 0) * F(2, 2) - F(0, 2) * F(2, 0);
  c(1, 2) = F(0, 1) * F(2, 0) - F(0, 0) * F(2, 1);
  c(2, 0) = F(0, 1) * F(1, 2) - F(0, 2) * F(1, 1);
  c(2, 1) = F(0, 2) * F(1, 0) - F(0, 0) * F(1, 2);
  c(2, 2) = F(0, 0) * F(1, 1) - F(0, 1) * F(1, 0);
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

bool NeoHookeanTetState(const TetReference& reference, const NeoHookeanParameters& p,
                        const CornerDisplacements& u, double& energy, ElementVector& force,
                        ElementMatrix* tangent) {
  const Eigen::Matrix3d F = DeformationGradient(reference, u);
  Eigen::Matrix3d cofactor;
  WriteCofactor(F, cofactor);
  const double J = F.row(0).dot(cofactor.row(0));
  if (!(J > 0.0))
    return false;
  const Eigen::Matrix<double, 4, 3>& G = reference.gradients;
  const double V = reference.volume;
  // NeoHookeanEnergyDensity and NeoHookeanStress with their shared terms computed once, F^-T as
  // cof(F) / J: this is the large-deformation solves' innermost loop. In this form the stress at
  // F = I is exactly zero.
  const double a = IsochoricFactor(J), i1 = F.squaredNorm();
  energy = V * (0.5 * p.mu * (a * i1 - 3.0) + 0.5 * p.kappa * (J - 1.0) * (J - 1.0));
  const double mua = p.mu * a;
  const Eigen::Matrix3d inverseT = cofactor / J;
  const Eigen::Matrix3d VP =
      V * (mua * (F - (i1 / 3.0) * inverseT) + p.kappa * (J - 1.0) * J * inverseT);
  // f_a = V P grad N_a.
  for (int c = 0; c < 4; ++c)
    force.segment<3>(3 * c).noalias() = VP * G.row(c).transpose();
  if (!tangent)
    return true;
  // The tangent's block (a, b), V grad N_a . dP/dF . grad N_b, in closed form. With H = F^-T,
  // dP/dF for dF = e_k e_l^T has the terms mu a delta_ik delta_jl, rank-one products of F and H,
  // and H_il H_kj; summed against the gradients each is an outer product of the corner vectors
  // F g and H g (g = grad N), so a block costs a few 3 x 3 outer products instead of nine stress
  // derivatives.
  const double crossFH = -(2.0 / 3.0) * mua; // (F g_a)(H g_b)^T + transpose
  const double alongH = (2.0 / 9.0) * mua * i1 + p.kappa * (2.0 * J - 1.0) * J; // (H g_a)(H g_b)^T
  const double swapH = mua * i1 / 3.0 - p.kappa * (J * J - J);                  // (H g_b)(H g_a)^T
  const Eigen::Matrix<double, 3, 4> h = inverseT * G.transpose(), fg = F * G.transpose();
  const Eigen::Matrix4d gg = G * G.transpose();
  for (int r = 0; r < 4; ++r)
    for (int c = r; c < 4; ++c) {
      Eigen::Matrix3d block =
          crossFH * (fg.col(r) * h.col(c).transpose() + h.col(r) * fg.col(c).transpose()) +
          alongH * h.col(r) * h.col(c).transpose() + swapH * h.col(c) * h.col(r).transpose();
      block.diagonal().array() += mua * gg(r, c);
      block *= V;
      if (c == r) // symmetric but for round-off in the products' order
        block = 0.5 * (block + block.transpose()).eval();
      tangent->block<3, 3>(3 * r, 3 * c) = block;
      if (c != r)
        tangent->block<3, 3>(3 * c, 3 * r) = block.transpose();
    }
  return true;
}

namespace {

// The four-lane kernel: forces, and with Tangent each lane's packed upper tangent as well.
template <bool Tangent>
[[gnu::always_inline]] inline bool TetLanes(NeoHookeanTetLanes& b, double (*tangent)[kTetLanes]) {
  constexpr int L = kTetLanes;
  double F[3][3][L];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < L; ++l)
        F[i][j][l] = (i == j ? 1.0 : 0.0) + b.corner[0][i][l] * b.gradient[0][j][l] +
                     b.corner[1][i][l] * b.gradient[1][j][l] +
                     b.corner[2][i][l] * b.gradient[2][j][l] +
                     b.corner[3][i][l] * b.gradient[3][j][l];
  double C[3][3][L], J[L], i1[L];
  for (int l = 0; l < L; ++l) {
    WriteCofactor([&](int i, int j) { return F[i][j][l]; },
                  [&](int i, int j) -> double& { return C[i][j][l]; });
    J[l] = F[0][0][l] * C[0][0][l] + F[0][1][l] * C[0][1][l] + F[0][2][l] * C[0][2][l];
    i1[l] = 0.0;
  }
  bool valid = true;
  for (int l = 0; l < L; ++l)
    valid &= J[l] > 0.0;
  if (!valid)
    return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < L; ++l)
        i1[l] += F[i][j][l] * F[i][j][l];
  double a[L], mua[L], third[L], volumetric[L];
  for (int l = 0; l < L; ++l)
    a[l] = IsochoricFactor(J[l]);
  for (int l = 0; l < L; ++l) {
    const double Jm1 = J[l] - 1.0;
    b.energy[l] =
        b.volume[l] * (0.5 * b.mu[l] * (a[l] * i1[l] - 3.0) + 0.5 * b.kappa[l] * Jm1 * Jm1);
    mua[l] = b.mu[l] * a[l];
    third[l] = i1[l] / 3.0;
    volumetric[l] = b.kappa[l] * Jm1 * J[l];
  }
  // V P with P = mu a (F - i1/3 F^-T) + kappa (J - 1) J F^-T, F^-T = cof / J (as the one cell's).
  double VP[3][3][L];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < L; ++l) {
        const double inverseT = C[i][j][l] / J[l];
        VP[i][j][l] =
            b.volume[l] * (mua[l] * (F[i][j][l] - third[l] * inverseT) + volumetric[l] * inverseT);
      }
  for (int c = 0; c < 4; ++c)
    for (int i = 0; i < 3; ++i)
      for (int l = 0; l < L; ++l)
        b.force[c][i][l] = VP[i][0][l] * b.gradient[c][0][l] + VP[i][1][l] * b.gradient[c][1][l] +
                           VP[i][2][l] * b.gradient[c][2][l];
  if constexpr (Tangent) {
    // NeoHookeanTetState's closed form with the lanes innermost: block (r, c) of the tangent is
    // V (crossFH ((F g_r)(H g_c)^T + (H g_r)(F g_c)^T) + alongH (H g_r)(H g_c)^T
    // + swapH (H g_c)(H g_r)^T + mu a (g_r . g_c) I), H = F^-T; a diagonal block is symmetric as
    // written, so only its upper triangle is formed.
    double fg[4][3][L], h[4][3][L], crossFH[L], alongH[L], swapH[L];
    for (int r = 0; r < 4; ++r)
      for (int i = 0; i < 3; ++i)
        for (int l = 0; l < L; ++l) {
          fg[r][i][l] = F[i][0][l] * b.gradient[r][0][l] + F[i][1][l] * b.gradient[r][1][l] +
                        F[i][2][l] * b.gradient[r][2][l];
          h[r][i][l] = (C[i][0][l] * b.gradient[r][0][l] + C[i][1][l] * b.gradient[r][1][l] +
                        C[i][2][l] * b.gradient[r][2][l]) /
                       J[l];
        }
    for (int l = 0; l < L; ++l) {
      crossFH[l] = -(2.0 / 3.0) * mua[l];
      alongH[l] = (2.0 / 9.0) * mua[l] * i1[l] + b.kappa[l] * (2.0 * J[l] - 1.0) * J[l];
      swapH[l] = mua[l] * i1[l] / 3.0 - b.kappa[l] * (J[l] * J[l] - J[l]);
    }
    int entry = 0;
    for (int p = 0; p < 12; ++p)
      for (int q = p; q < 12; ++q, ++entry) {
        const int r = p / 3, i = p % 3, c = q / 3, j = q % 3;
        double* out = tangent[entry];
        for (int l = 0; l < L; ++l) {
          double v = crossFH[l] * (fg[r][i][l] * h[c][j][l] + h[r][i][l] * fg[c][j][l]) +
                     alongH[l] * h[r][i][l] * h[c][j][l] + swapH[l] * h[c][i][l] * h[r][j][l];
          if (i == j)
            v += mua[l] * (b.gradient[r][0][l] * b.gradient[c][0][l] +
                           b.gradient[r][1][l] * b.gradient[c][1][l] +
                           b.gradient[r][2][l] * b.gradient[c][2][l]);
          out[l] = b.volume[l] * v;
        }
      }
  }
  return true;
}

} // namespace

// Four-wide AVX2 where the CPU has it (the build's baseline is SSE2's two), chosen at load time.
// Without FMA contraction, so that both versions give the same bits.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
bool NeoHookeanTetForces(NeoHookeanTetLanes& b) {
  return TetLanes<false>(b, nullptr);
}

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
bool NeoHookeanTetForcesAndTangents(NeoHookeanTetLanes& b,
                                    double (*tangent)[kTetLanes]) {
  return TetLanes<true>(b, tangent);
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
