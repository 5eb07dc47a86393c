// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The tetrahedral mesh and its per-cell materials, as Core sees them (no VTK).
#include "Common/RowVectors3d.h"

#include <Eigen/Core>

#include <vector>

namespace faceplan {

using Tets = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;

struct TetMesh {
  RowVectors3d points; // n x 3
  Tets tets;           // m x 4, positively oriented (det[x1-x0, x2-x0, x3-x0] > 0)

  Eigen::Index numPoints() const { return points.rows(); }
  Eigen::Index numTets() const { return tets.rows(); }
};

// Isotropic linear elasticity per cell. Each vector has one entry per tetrahedron, or a single
// entry that applies to every tetrahedron (a one-tissue scene).
struct Materials {
  Eigen::VectorXd youngsModulus; // E > 0, in the caller's stress unit
  Eigen::VectorXd poissonRatio;  // -1 < nu < 0.5
  Eigen::VectorXd density;       // mass per volume; only used with a gravity load; may be empty
  // 1 for cells that the large-deformation model keeps small-strain (linear) elastic: LipSeal's
  // bridges, a penalty weld whose constant tangent the precomputed factor then holds exactly.
  // One entry per tetrahedron, or empty (none). The linear model is linear everywhere anyway.
  std::vector<unsigned char> smallStrain;

  static Materials Uniform(double E, double nu, double rho = 0.0) {
    Materials m;
    m.youngsModulus = Eigen::VectorXd::Constant(1, E);
    m.poissonRatio = Eigen::VectorXd::Constant(1, nu);
    m.density = Eigen::VectorXd::Constant(1, rho);
    return m;
  }
  double E(Eigen::Index cell) const {
    return youngsModulus.size() == 1 ? youngsModulus[0] : youngsModulus[cell];
  }
  double nu(Eigen::Index cell) const {
    return poissonRatio.size() == 1 ? poissonRatio[0] : poissonRatio[cell];
  }
  bool isSmallStrain(Eigen::Index cell) const {
    return !smallStrain.empty() && smallStrain[static_cast<size_t>(cell)] != 0;
  }
  double rho(Eigen::Index cell) const {
    if (density.size() == 0)
      return 0.0;
    return density.size() == 1 ? density[0] : density[cell];
  }
};

} // namespace faceplan
