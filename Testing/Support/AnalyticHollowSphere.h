// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Thick hollow sphere (inner radius a, outer b), radial displacement ua prescribed on the inner
// surface, free outer surface: u(r) = A r + B / r^2 with sigma_rr(b) = 0. The exact solution the
// convergence test and the error-versus-time report measure discretisation error against.
// Header-only, VTK-free.
#include "Element/ElementStiffness.h"
#include "Mesh/TetMesh.h"

#include <cmath>

namespace faceplan {

struct HollowSphere {
  double a = 1.0, b = 2.0, ua = 0.01, E = 1.0, nu = 0.3;
  double A = 0, B = 0;
  HollowSphere() { update(); }
  // Recomputes A and B after a, b, ua, E or nu changed.
  void update() {
    double lambda, mu;
    LameParameters(E, nu, lambda, mu);
    // sigma_rr(b) = (3 lambda + 2 mu) A - 4 mu B / b^3 = 0 and A a + B / a^2 = ua.
    const double ratio = 4.0 * mu / ((3.0 * lambda + 2.0 * mu) * b * b * b); // A = ratio * B
    B = ua / (ratio * a + 1.0 / (a * a));
    A = ratio * B;
  }
  Eigen::Vector3d displacement(const Eigen::Vector3d& x) const {
    const double r = x.norm();
    return (A * r + B / (r * r)) * x / r;
  }
};

// L2 norm of the error of nodal displacements u (one row per mesh point) over the mesh, with the
// degree-2 four-point rule per tetrahedron; l2Exact receives the exact solution's L2 norm.
inline double HollowSphereL2Error(const TetMesh& mesh, const RowVectors3d& u,
                                  const HollowSphere& exact, double& l2Exact) {
  const double alpha = 0.5854101966249685, beta = 0.1381966011250105;
  double err2 = 0.0, ref2 = 0.0;
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k)
      c.row(k) = mesh.points.row(mesh.tets(e, k));
    const double w = TetVolume(c) / 4.0;
    for (int q = 0; q < 4; ++q) {
      Eigen::Vector4d bary = Eigen::Vector4d::Constant(beta);
      bary[q] = alpha;
      Eigen::Vector3d x = Eigen::Vector3d::Zero(), uh = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        x += bary[k] * c.row(k).transpose();
        uh += bary[k] * u.row(mesh.tets(e, k)).transpose();
      }
      const Eigen::Vector3d ue = exact.displacement(x);
      err2 += w * (uh - ue).squaredNorm();
      ref2 += w * ue.squaredNorm();
    }
  }
  l2Exact = std::sqrt(ref2);
  return std::sqrt(err2);
}

} // namespace faceplan
