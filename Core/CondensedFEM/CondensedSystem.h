// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What Precompute() builds and Solve() reads: a documented public struct, not an opaque handle.
// The assembled blocks, the factor and the dense response are exactly what the comparison paths,
// the GPU tests and the benchmarks check against, so they read them here rather than through an
// inspection API that would copy them. Precompute() is the only writer; callers hold it as
// std::shared_ptr<const CondensedSystem>, so every field is read-only after the precompute (the
// load cache below is the one mutable part, guarded by its mutex). SystemInfo (Describe()) is the
// summary for callers that need no more. CHOLMOD stays behind CholmodFactor's pimpl: including
// this header does not include cholmod.h.
#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/NodeLayout.h"
#include "SparseSolver/CholmodFactor.h"

#include <array>
#include <mutex>

namespace faceplan {

class CondensedSystem {
public:
  SolveMethod method = SolveMethod::CachedFactor; // the method chosen (Auto resolved)
  std::string backendName;                        // the backend that assembled (and condensed)
  Eigen::Index numMeshNodes = 0;                  // solver nodes (TET10: corners + mid-edge nodes)
  NodeLayout layout;                              // DOF numbering: kept, interior, ROI blocks
  std::vector<int> kept;                          // NodeSets::kept as given
  bool keptIsFreeBlock =
      false; // kept[k] is free position k, none sliding: the kept-free values are the rows

  SparseMatrix kff; // upper triangle, free x free
  SparseMatrix kfr; // free x ROI DOFs (NodeLayout::roiDofs)
  CholmodFactor factor;

  Eigen::MatrixXd
      response; // kept-free DOFs x ROI DOFs (DenseResponse) or x parameters (RigidSegments)
  std::unique_ptr<ResponseOperator> responseOperator;
  double responseResidual = 0.0;

  Eigen::VectorXd nodeMass; // lumped rho*V/4 per free node, for gravity
  SystemInfo info;          // what Describe() returns

  // Quadratic elements: the caller's movable list is followed by mid-edge ROI nodes, whose value
  // is the mean of their two ends, given as indices into the caller's movable list (-1: fixed end).
  std::vector<std::array<int, 2>> derivedMovable;
  Eigen::Index numOutputNodes = 0; // the caller's node count (corner nodes)
  TetMesh cornerMesh;              // the caller's linear mesh, for the deformation check
  std::vector<int> movableNodes;   // NodeSets::movable as given
  std::vector<int> checkableCells; // cells whose corners are all kept or constrained
  double residualTolerance = 1e-10;
  int maxRefinementSteps = 3;
  double strainWarningLimit = 0.1;
  std::string precisionNote; // set when the response operator is not plain double
  bool responseRedoneInDouble = false;

  // ROI DOF values from the caller's movable displacements (3 per node, node-major): the
  // displacement itself, the mean of the ends for a mid-edge node, the normal part for a sliding
  // one.
  SparseMatrix movableToRoi;
  // RigidSegments: the ROI DOFs as a function of the segment parameters (RigidSegments.h).
  SparseMatrix segmentToRoi;
  NodeSets segmentSets; // movable nodes and their segment ids, as given
  int segments = 0;
  // RigidSegments: the checkable cells by decreasing strain gain, and each segment's centroid and
  // RMS radius that rescale its parameters (DeformationCheck.h); empty when every edit checks all.
  struct BoundedCell {
    int cell = -1;
    double gain = 0.0;            // ||grad u||_F <= gain * (scaled parameter norm)
    std::array<int, 4> source{};  // corner: kept row k >= 0, movable row -(m + 2), or -1 (fixed)
    Eigen::Matrix3d inverseEdges; // of the undeformed edges x_j - x_0
  };
  std::vector<BoundedCell> boundedCells;
  std::vector<Eigen::Vector3d> segmentCentre;
  std::vector<double> segmentLength;
  double meshExtent = 0.0; // diagonal of the caller's mesh bounds (segment displacement tolerance)

  // Sliding nodes (free positions whose DOFs are in the node's normal frame: local DOF 0 is the
  // normal one, pinned in K_FF; its prescribed value reaches the others through a K_FR column).
  std::vector<int> slidingOfPosition;        // free position -> sliding index, -1 when not sliding
  std::vector<Eigen::Matrix3d> slidingFrame; // columns: normal, two tangents
  std::vector<int> slidingRoiDof;            // the normal value's ROI DOF, -1 when fixed (0)

  // Response of the free DOFs to the last load vector, reused while loads do not change.
  mutable std::mutex loadMutex;
  mutable Eigen::VectorXd lastLoad, lastLoadResponse;
};

} // namespace faceplan
