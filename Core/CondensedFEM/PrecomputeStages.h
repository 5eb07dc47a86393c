#pragma once
// The precompute, one function per Stage (Common/StageTimings.h), in the order Precompute runs
// them. Each adds its time to the system's stage table and returns an error or Ok; warnings
// accumulate in PrecomputeState::status.
#include "Backend/ComputeBackend.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Element/QuadraticTet.h"
#include "Element/StiffnessAssembly.h"

#include <atomic>
#include <memory>

namespace faceplan {

// What the stages hand on to each other.
struct PrecomputeState {
  PrecomputeState(const PrecomputeRequest& r, const std::atomic<bool>* c, const ProgressCallback& p)
      : request(r), cancel(c), progress(p), sys(std::make_shared<CondensedSystem>()) {}
  const PrecomputeRequest& request;
  const std::atomic<bool>* cancel;
  const ProgressCallback& progress;
  std::shared_ptr<CondensedSystem> sys;
  Status status = Status::Ok(); // carries the warnings
  StageClock clock;             // lapped by each stage

  bool quadratic = false, nodalPressure = false;
  QuadraticMesh qmesh;     // quadratic only, until the blocks are separated
  AssemblyPattern pattern; // the assembled upper triangle, until the blocks are separated
  std::shared_ptr<ComputeBackend> backend;
  std::unique_ptr<ResponseOperator> backendOperator; // when the backend built the response
  bool backendResponse = false;
  // Rigid segments (when the method may be RigidSegments): K_FR times the ROI DOFs' dependence on
  // the segment parameters, the right-hand sides of the response's columns.
  SparseMatrix segmentCoupling;

  bool cancelled() const { return cancel && cancel->load(); }
  void report(double fraction, const char* what) const {
    if (progress)
      progress(fraction, what);
  }
  StageTime& time(Stage s) { return sys->info.precomputeTimings[s]; }
};

// Checks the mesh, materials, node sets and options; records element quality warnings.
Status ValidatePrecomputeRequest(PrecomputeState& state);

// Separation, first part: node classes (and, for quadratic cells, the TET10 mesh with its
// extended node sets) and the DOF layout the assembly scatters into.
Status SeparateNodes(PrecomputeState& state);

// ElementStiffness and Assembly: a backend computes and scatters the element matrices in one call,
// so both stages are one function; each keeps its own time.
Status AssembleStiffness(PrecomputeState& state);

// Separation, second part: K_FF and K_FR from the assembled matrix (sliding nodes' DOFs rotated
// into their normal frames and the normal DOF moved to the ROI side), the free nodes' masses.
Status SeparateBlocks(PrecomputeState& state);

// Reordering: the fill-reducing ordering of K_FF and its symbolic analysis.
Status ReorderFreeDofs(PrecomputeState& state);

// Picks the solve method from the sizes (needs only the analysis), within the memory budget: an
// error when the factor or a requested response would not fit. Untimed: it is arithmetic.
Status ChooseSolveMethod(PrecomputeState& state);

// Factorization of K_FF (a backend may build the dense response in the same call).
Status Factorize(PrecomputeState& state);

// Condensation: the dense response of the kept DOFs to the ROI DOFs (DenseResponse) or to the
// segment parameters (RigidSegments), and its per-edit operator.
Status Condense(PrecomputeState& state);

} // namespace faceplan
