#pragma once
// Internal layout of a precomputed system (not part of the public interface; shared by
// CondensedFEM.cpp and the report tools that need the assembled blocks).
#include "CholmodFactor.h"
#include "CondensedFEM.h"

#include <mutex>

namespace faceplan {

// Node numbering of the DOF blocks: free nodes first (kept, then interior), then ROI nodes.
// Constrained nodes outside the ROI and unused nodes have no DOFs (they never move).
struct NodeLayout {
  std::vector<int> dofNode;  // mesh node -> position in the blocks, -1 when it has no DOFs
  std::vector<int> meshNode; // position -> mesh node
  int keptFree = 0, interior = 0, roi = 0;
  int freeNodes() const { return keptFree + interior; }
  std::vector<int> roiPosition; // NodeSets::movable index -> ROI position (0-based within ROI)
};

class CondensedSystem {
public:
  SolveMethod method = SolveMethod::CachedFactor;
  std::string backendName;
  Eigen::Index numMeshNodes = 0;
  NodeLayout layout;
  std::vector<int> kept; // NodeSets::kept as given

  SparseMatrix kff; // upper triangle, free x free
  SparseMatrix kfr; // free x ROI
  CholmodFactor factor;

  Eigen::MatrixXd response; // kept-free DOFs x ROI DOFs (DenseResponse)
  std::unique_ptr<ResponseOperator> responseOperator;
  double responseResidual = 0.0;

  Eigen::VectorXd nodeMass; // lumped rho*V/4 per free node, for gravity
  SystemInfo info;

  // Response of the free DOFs to the last load vector, reused while loads do not change.
  mutable std::mutex loadMutex;
  mutable Eigen::VectorXd lastLoad, lastLoadResponse;
};

} // namespace faceplan
