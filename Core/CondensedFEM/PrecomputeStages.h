// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The precompute, one function per Stage (Common/StageTimings.h), in the order Precompute runs
// them. Each adds its time to the system's stage table and returns an error or Ok; warnings
// accumulate in PrecomputeState::status.
#include "Backend/ComputeBackend.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Element/QuadraticTet.h"
#include "Element/StiffnessAssembly.h"

#include <atomic>
#include <future>
#include <memory>
#include <string>
#include <vector>

namespace faceplan {

// The ordering and symbolic analysis made beside the assembly (StartEarlyOrdering), with the
// inputs it used, which ReorderFreeDofs checks against the separated blocks.
struct EarlyOrdering {
  Status status = Status::Ok();
  std::string ordering; // SystemInfo::ordering
  double ms = 0.0;
  SparseMatrix kffPattern;   // the K_FF structure it analysed
  std::vector<char> coupled; // the free nodes it took as K_FR's rows
};

// The mesh checks of the validation that need the shared faces (held rigid modes, element
// quality, folded faces), made beside the separation and assembly.
struct MeshChecks {
  Status status = Status::Ok(); // an error when a piece is not held; its warnings otherwise
  long long sliverCells = 0;
  double worstQuality = 1.0;
  long long foldedFaces = 0;
  double ms = 0.0;
};

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

  size_t meshCheckWarningsAt = 0; // where the mesh checks' warnings go among the warnings
  // Work running on its own thread; declared last, so destroyed (waited for) first.
  std::future<MeshChecks> meshChecks;
  std::future<EarlyOrdering> earlyOrdering;

  bool cancelled() const { return cancel && cancel->load(); }
  void report(double fraction, const char* what) const {
    if (progress)
      progress(fraction, what);
  }
  StageTime& time(Stage s) { return sys->info.precomputeTimings[s]; }
};

// Checks the mesh, materials, node sets and options, and starts the mesh checks (MeshChecks) on
// their own thread.
Status ValidatePrecomputeRequest(PrecomputeState& state);

// Waits for the mesh checks: their error (a piece not held), or their warnings and figures.
Status FinishMeshChecks(PrecomputeState& state);

// Separation, first part: node classes (and, for quadratic cells, the TET10 mesh with its
// extended node sets) and the DOF layout the assembly scatters into.
Status SeparateNodes(PrecomputeState& state);

// ElementStiffness and Assembly: a backend computes and scatters the element matrices in one call,
// so both stages are one function; each keeps its own time.
Status AssembleStiffness(PrecomputeState& state);

// Separation, second part: K_FF and K_FR from the assembled matrix (sliding nodes' DOFs rotated
// into their normal frames and the normal DOF moved to the ROI side), the free nodes' masses.
Status SeparateBlocks(PrecomputeState& state);

// Starts the ordering and symbolic analysis of K_FF on its own thread from the cells' node graph,
// where K_FF's structure follows from it alone (no sliding nodes, no nodal pressure). False when
// it did not start.
bool StartEarlyOrdering(PrecomputeState& state, std::shared_ptr<const NodeNeighbours> lower);

// Reordering: the fill-reducing ordering of K_FF and its symbolic analysis (waits for the early
// one when it was started, and checks it was made for these blocks).
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
