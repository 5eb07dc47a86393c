// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The free system K_FF u_F = f_F - K_FR u_R of a scene, assembled once, for the solve paths that
// are not Core's condensed one (conjugate gradients, single precision, mass-spring comparisons).
// The DOF numbering follows CondensedFEM's layout: free nodes first (kept, then interior), then
// the ROI nodes; constrained nodes outside the ROI have no DOFs.
#include "CondensedFEM/CondensedFEM.h"
#include "Element/StiffnessAssembly.h"

#include <vector>

namespace faceplan {

struct FreeSystem {
  Eigen::Index numMeshNodes = 0;
  std::vector<int> dofNode;  // mesh node -> block position, -1 without DOFs
  std::vector<int> meshNode; // block position -> mesh node
  int keptFree = 0, interior = 0, roi = 0;
  std::vector<int> roiPosition; // NodeSets::movable index -> ROI position, -1 when unused
  std::vector<int> kept;        // NodeSets::kept as given
  SparseMatrix kff;             // upper triangle, free x free
  SparseMatrix kfr;             // free x ROI (full block)
  double elementStiffnessMs = 0.0, assemblyMs = 0.0;

  int freeNodes() const { return keptFree + interior; }
  int freeDofs() const { return 3 * freeNodes(); }
};

// Validates the request and assembles K_FF and K_FR (element stiffness and assembly threaded).
Status BuildFreeSystem(const PrecomputeRequest& request, FreeSystem& system);

// The ROI vector u_R (3 per ROI node) from NodeSets::movable-ordered displacements.
Status RoiVector(const FreeSystem& system, const RowVectors3d& movable, Eigen::VectorXd& roi);

// Right-hand side f_F - K_FR u_R (no loads).
Eigen::VectorXd FreeRightHandSide(const FreeSystem& system, const Eigen::VectorXd& roi);

// Kept (NodeSets::kept order) or all nodes' displacement from free values and the ROI vector.
RowVectors3d KeptDisplacement(const FreeSystem& system, const Eigen::VectorXd& freeValues,
                              const Eigen::VectorXd& roi);
RowVectors3d AllDisplacement(const FreeSystem& system, const Eigen::VectorXd& freeValues,
                             const Eigen::VectorXd& roi);

// ||K_FF x - b|| / ||b||.
double FreeRelativeResidual(const FreeSystem& system, const Eigen::VectorXd& x,
                            const Eigen::VectorXd& b);

} // namespace faceplan
