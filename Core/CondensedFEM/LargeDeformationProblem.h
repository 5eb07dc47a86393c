// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The neo-Hookean equilibrium that both large-deformation solves share (LargeDeformation.cpp's
// Newton and PrecomputedLargeDeformation.cpp): each node's frame (a sliding node's frame is its
// normal and two tangents, every other node's the identity), so that each prescribed value is one
// DOF; the cells' energy, force and tangent; the convergence yardstick; lift-off's active set.
// Private to FacePlanCondensedFEM.
#include "CondensedFEM/CondensedFEM.h"
#include "Element/NeoHookeanTet.h"
#include "Element/StiffnessAssembly.h"

#include <memory>
#include <vector>

namespace faceplan {
namespace large_deformation {

// What depends on the mesh, materials and node sets only: shared by every solve.
struct Structure {
  // The request's mesh with its cells reordered along a space-filling curve (ownMesh), so that
  // cells taken one after another share nodes: the cell loops then find their nodes' values in
  // the cache, where the request's own cell numbering has no locality. meshCell: per cell here,
  // its index in the request's mesh (what reports say).
  const TetMesh* mesh = nullptr;
  std::shared_ptr<const TetMesh> ownMesh;
  std::vector<int> meshCell;
  long long requestCell(long long cell) const {
    return cell < 0 || cell >= static_cast<long long>(meshCell.size()) ? cell : meshCell[cell];
  }
  // The cell ranges of Evaluate (EvaluationScratch::kRanges of them): per range, the nodes its
  // cells use (ascending), and per cell corner its node's place in its range's list. Each range
  // sums its cells' forces over its own nodes only, a few thousand where the mesh has tens of
  // thousands, so that its sum is cleared and added in a fraction of the time.
  std::vector<std::vector<int>> rangeNodes;
  std::vector<int> cornerSlot; // 4 per cell
  Eigen::Index n = 0;
  std::vector<int> frameOf;            // node -> index into frames, -1 for the identity
  std::vector<Eigen::Matrix3d> frames; // columns: normal, two tangents
  std::vector<TetReference> cells;
  std::vector<NeoHookeanParameters> materials;
  std::vector<char> smallStrain; // per cell: small-strain elastic (Materials::smallStrain)
  std::vector<double> cellMass;  // rho * volume (gravity's dead load)
  // Prescribed DOFs before lift-off: every DOF of a constrained node (only the normal one when
  // sliding) and of a node no cell uses.
  std::vector<char> prescribed;
  // Sliding nodes' normal DOFs when the tissue may lift off the bone (unilateral contact).
  std::vector<int> liftOffDofs;
  // |K_0 X| for the node positions X: the force of a unit strain. A small fraction of it is the
  // yardstick's floor, where the stress's cancellation (F against F^-T near the identity) leaves
  // round-off in the residual that a relative tolerance cannot get below.
  double unitStrainForce = 0.0;

  Eigen::Vector3d toGlobal(int node, const Eigen::Vector3d& local) const {
    return frameOf[node] < 0 ? local : Eigen::Vector3d(frames[frameOf[node]] * local);
  }
  Eigen::Vector3d toLocal(int node, const Eigen::Vector3d& global) const {
    return frameOf[node] < 0 ? global : Eigen::Vector3d(frames[frameOf[node]].transpose() * global);
  }
};

// One solve's values: the prescribed DOFs (lift-off changes them), their targets and the loads.
struct Problem {
  std::shared_ptr<const Structure> st;
  std::vector<char> prescribed; // per DOF, in the node's frame
  Eigen::VectorXd target;       // prescribed DOFs' values, 0 elsewhere
  Eigen::VectorXd externalLoad; // dead load, in the nodes' frames
  // The force the linear model needs for the whole prescribed move (|K_0 u_prescribed|): the
  // residual's yardstick where the internal forces vanish, as in a rigid motion.
  double linearForce = 0.0;
};

// Frames, cells, materials and the prescribed DOFs of `request` (validated by the caller).
Status MakeStructure(const PrecomputeRequest& request, bool liftOff, Structure& st);
// The node-graph assembly pattern of the whole mesh (identity numbering).
Status MakePattern(const Structure& st, AssemblyPattern& pattern);
// Targets and loads of `input` (in the nodes' frames) into pb, whose st and prescribed are set.
Status SetValues(const PrecomputeRequest& request, const SolveInput& input, Problem& pb);

// Internal energy, internal force and (when packed is given) the packed tangents at u (nodes'
// frames). False when a cell would be inverted or degenerate.
struct Evaluation {
  double energy = 0.0;
  Eigen::VectorXd force;
};
// Buffers a solver keeps for its evaluations: a solve evaluates many times, and fresh megabytes
// each time cost more in page faults than the element loop itself. Optional.
struct EvaluationScratch {
  static constexpr int kRanges = 8; // cell ranges, each with its own force sum
  std::vector<double> energy;
  std::vector<Eigen::VectorXd> force;
  std::vector<char> valid;
  std::vector<std::vector<int>> order; // per range, with NearRestTangents: its cells, far first
};
// Cells near rest keep their rest tangent (for a tangent that only preconditions, as the
// precomputed solve's factor does): a neo-Hookean cell whose deformation gradient is within `limit`
// of the identity (largest entry of F - I) gets `rest`'s packed tangent instead of its own.
// `held` (one flag per cell, kept with the packed buffer) says whether the buffer already holds a
// cell's rest tangent, so that only cells that come near rest again are copied.
struct NearRestTangents {
  const std::vector<double>* rest = nullptr;
  std::vector<char>* held = nullptr;
  double limit = 0.0;
};
bool Evaluate(const Structure& st, const Eigen::VectorXd& u, Evaluation& out,
              std::vector<double>* packed, EvaluationScratch* scratch = nullptr,
              const NearRestTangents* nearRest = nullptr);

// v: a vector or a matrix's column.
void ZeroPrescribed(const std::vector<char>& prescribed, Eigen::Ref<Eigen::VectorXd> v);

// The nonzeros of `upper` in a prescribed row or column, off the diagonal and on it.
void FindPinnedEntries(const SparseMatrix& upper, const std::vector<char>& prescribed,
                       std::vector<int>& entries, std::vector<int>& diagonal);

// Strains below this are measured against the unit-strain force instead (see unitStrainForce).
constexpr double kRoundOffStrain = 1e-5;
// The relative residual at which lift-off's contact is updated before the final solve.
constexpr double kSettleTolerance = 1e-6;

// Total potential energy and the free DOFs' residual at u for the load fraction s.
struct Balance {
  double potential = 0.0;
  Eigen::VectorXd residual;  // zero on prescribed DOFs
  double residualNorm = 0.0; // |residual|
  double scale = 0.0;        // what the residual is measured against
};
Balance BalanceOf(const Problem& pb, const Evaluation& ev, const Eigen::VectorXd& u, double s);
// The same into `b`, reusing its residual's memory (an iteration's hot path).
void BalanceInto(const Problem& pb, const Evaluation& ev, const Eigen::VectorXd& u, double s,
                 Balance& b);

// Unilateral contact at a converged state u for the load fraction s: a node in contact whose
// contact force pulls it onto the bone (a negative normal residual) lifts off, a lifted node that
// has gone into the bone comes back into contact. True when a node changed. `force`: the internal
// force at u when the caller has it (else it is evaluated).
bool UpdateContact(Problem& pb, const Eigen::VectorXd& u, double s,
                   const Eigen::VectorXd* force = nullptr);

struct DeformationMeasures {
  double smallestVolumeRatio = 1.0;
  double largestGreenStrain = 0.0;
  long long largestStrainCell = -1;
};
DeformationMeasures MeasureDeformation(const Structure& st, const Eigen::VectorXd& u);

// |K_0 v| and |K_0 X| from the rest tangent (for the yardstick).
double RestForceNorm(const SparseMatrix& restUpper, const Eigen::VectorXd& v);
Eigen::VectorXd LocalPositions(const Structure& st);

// Every node's displacement (global frame) into result's kept rows and, with recoverInterior, all.
Status FillResult(const PrecomputeRequest& request, const SolveInput& input, const Structure& st,
                  const Eigen::VectorXd& u, SolveResult& result);

// What both solvers report of their final state u: its measures and lifted nodes, and the result
// (rows, residual, largest strain) through FillResult.
struct FinalState {
  DeformationMeasures measures;
  int liftedNodes = 0; // lift-off DOFs not pinned at u
};
// `measured`: the measures of u when the caller has them (else they are computed here).
Status FinishSolve(const PrecomputeRequest& request, const SolveInput& input, const Problem& pb,
                   const Eigen::VectorXd& u, double relativeResidual, SolveResult& result,
                   FinalState& finalState, const DeformationMeasures* measured = nullptr);

} // namespace large_deformation
} // namespace faceplan
