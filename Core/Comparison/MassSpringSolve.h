// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A light-weight non-FEM model on the same mesh, the kind the ICAT 2008 paper contrasts FEM with:
// linear springs on the tetrahedra's edges, stiffness k = E * (sum of the volumes of the tets
// sharing the edge) / L^2 (Van Gelder's 1998 rule for an isotropic material; Poisson's ratio has
// no counterpart), linearised about the rest shape (k n n^T per edge) and solved statically with
// the same boundary conditions (constrained nodes held, ROI prescribed) by a sparse Cholesky.
// Its difference to FEM is modelling error, not solver error. Never throws.
#include "CondensedFEM/CondensedFEM.h"
#include "SparseSolver/CholmodFactor.h"

namespace faceplan {

class MassSpringModel {
public:
  // Springs, assembly and the factorization of the free block (the precompute).
  Status build(const PrecomputeRequest& request);
  // Kept nodes' displacement (NodeSets::kept order) for prescribed ROI displacements; with `all`
  // non-null also every node's.
  Status solve(const RowVectors3d& movable, RowVectors3d& kept, RowVectors3d* all = nullptr) const;

  long long springs() const { return springs_; }
  double buildMs() const { return buildMs_; }
  double factorizeMs() const { return factorizeMs_; }

private:
  Eigen::Index numNodes_ = 0;
  long long springs_ = 0;
  double buildMs_ = 0.0, factorizeMs_ = 0.0;
  std::vector<int> freeIndex_, prescribedIndex_, movableToPrescribed_, kept_;
  int numFree_ = 0, numPrescribed_ = 0;
  SparseMatrix kffUpper_, kfp_;
  CholmodFactor factor_;
  bool ready_ = false;
};

} // namespace faceplan
