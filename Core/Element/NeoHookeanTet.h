// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Compressible neo-Hookean tetrahedron for large deformations (total Lagrangian, linear shape
// functions, so the deformation gradient F is constant per cell).
//
// Strain energy per reference volume, with J = det F and C = F^T F:
//   W = mu / 2 (J^(-2/3) tr C - 3) + kappa / 2 (J - 1)^2,
// CalculiX's *HYPERELASTIC, NEO HOOKE (C10 = mu / 2, D1 = 2 / kappa). Its small-strain limit is
// linear elasticity with shear modulus mu and bulk modulus kappa, so with the parameters below it
// agrees with the linear model for small moves and stays valid for large strains and rotations.
#include "Element/ElementStiffness.h"
#include "Mesh/TetGeometry.h"

#include <Eigen/Core>

namespace faceplan {

struct NeoHookeanParameters {
  double mu = 0.0;    // shear modulus
  double kappa = 0.0; // bulk modulus
};
// The parameters whose small-strain limit is the linear material (E, nu).
NeoHookeanParameters NeoHookeanFromLinear(double E, double nu);

// What a cell needs from its undeformed shape.
struct TetReference {
  Eigen::Matrix<double, 4, 3> gradients; // d N_a / d X, one row per corner
  double volume = 0.0;
};
TetReference MakeTetReference(const TetCorners& corners);

using ElementVector = Eigen::Matrix<double, 12, 1>;
using CornerDisplacements = Eigen::Matrix<double, 4, 3>; // one corner per row

// F = I + sum_a u_a (x) grad N_a.
// Inline: the large-deformation solves' innermost loop calls it per cell and evaluation.
inline Eigen::Matrix3d DeformationGradient(const TetReference& reference,
                                           const CornerDisplacements& u) {
  return Eigen::Matrix3d::Identity() + u.transpose() * reference.gradients;
}

// Strain energy density W(F) and the first Piola-Kirchhoff stress P = dW/dF. Requires det F > 0.
double NeoHookeanEnergyDensity(const Eigen::Matrix3d& F, const NeoHookeanParameters& p);
Eigen::Matrix3d NeoHookeanStress(const Eigen::Matrix3d& F, const NeoHookeanParameters& p);

// The cell's energy, internal force (dE/du, DOF order node0 x,y,z, node1 ...) and, when `tangent`
// is given, its derivative (12 x 12, symmetric). False, with nothing written, when det F <= 0.
bool NeoHookeanTetState(const TetReference& reference, const NeoHookeanParameters& p,
                        const CornerDisplacements& u, double& energy, ElementVector& force,
                        ElementMatrix* tangent);

// Four cells' energies and internal forces at once (no tangent), lane l holding cell l: the
// expressions of NeoHookeanTetState's force with the lanes innermost, so that the compiler
// vectorizes them across cells (one cell's 3 x 3 algebra is too short and too serial for it).
// The force solves' innermost loop; equal to NeoHookeanTetState to round-off.
constexpr int kTetLanes = 4;
struct NeoHookeanTetLanes {
  // In: the corners' displacements and grad N_a (index [corner][component][lane]), the volumes
  // and the moduli.
  double corner[4][3][kTetLanes];
  double gradient[4][3][kTetLanes];
  double volume[kTetLanes], mu[kTetLanes], kappa[kTetLanes];
  // Out: each lane's energy and force (dE/du_a, [corner][component][lane]).
  double energy[kTetLanes];
  double force[4][3][kTetLanes];
};
// False, with the outputs unspecified, when any lane's det F <= 0.
bool NeoHookeanTetForces(NeoHookeanTetLanes& lanes);
// The same, and each lane's tangent (NeoHookeanTetState's to round-off) into tangent[entry][lane]:
// its upper triangle row by row (78 entries, the packed order of ElementStiffness.h).
bool NeoHookeanTetForcesAndTangents(NeoHookeanTetLanes& lanes, double (*tangent)[kTetLanes]);

// The same cell with small-strain linear elasticity of the same moduli (shear mu, bulk kappa):
// W = mu eps:eps + (kappa - 2 mu / 3) / 2 (tr eps)^2 with eps the symmetric part of F - I. Its
// force is linear in u and its tangent constant. For cells that are no tissue (LipSeal's bridges).
// False, with nothing written, when det F <= 0: the solvers keep every cell uninverted, these too.
bool SmallStrainTetState(const TetReference& reference, const NeoHookeanParameters& p,
                         const CornerDisplacements& u, double& energy, ElementVector& force,
                         ElementMatrix* tangent);

} // namespace faceplan
