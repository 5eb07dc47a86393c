#pragma once
// Linear static FEM on tetrahedra with interior condensation, split libigl-style into a precompute
// (mesh, materials, node sets) and a solve (prescribed ROI displacements and loads).
//
// Node classes: constrained (tied to bone), of which the `movable` subset (the ROI) receives
// prescribed displacements and the rest stay at zero; kept (the caller needs their displacement,
// typically the skin); interior (everything else, condensed out). Because only ROI DOFs ever carry
// prescribed values, an edit needs nothing but the response of the kept DOFs to the ROI DOFs.
#include "ComputeBackend.h"
#include "StageTimings.h"
#include "Status.h"
#include "TetMesh.h"

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace faceplan {

struct NodeSets {
  std::vector<int> constrained; // nodes with prescribed displacement
  std::vector<int> movable;     // subset of constrained: the ROI; the others are fixed at zero
  std::vector<int> kept;        // nodes reported by every solve (may include constrained nodes)
};

enum class SolveMethod {
  Auto,           // pick the cheapest exact method from the sizes (see ChooseMethod)
  DenseResponse,  // precompute kept x ROI response; an edit is one matrix-vector product
  CachedFactor,   // keep the sparse Cholesky factor of the free block; an edit is one solve
  FullReference   // no condensation, no cache: assemble and factor everything on every solve
};
const char* MethodName(SolveMethod method);

struct PrecomputeOptions {
  SolveMethod method = SolveMethod::Auto;
  // Largest dense response Auto may build, in bytes.
  double denseResponseBudgetBytes = 2.0e9;
  // Compute backend for element stiffness, assembly and the dense per-edit update; null = CPU.
  std::shared_ptr<ComputeBackend> backend;
  // Columns of the response solved per block (bounds the precompute's transient memory).
  int responseBlockColumns = 256;
};

struct SolveInput {
  Displacements movableDisplacement; // |movable| x 3, in NodeSets::movable order
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero(); // body load density * gravity, if non-zero
  Displacements nodalLoads;          // n x 3 or empty
  bool recoverInterior = false;      // also return every node's displacement
};

struct SolveResult {
  Displacements keptDisplacement; // |kept| x 3, in NodeSets::kept order
  Displacements allDisplacement;  // n x 3 when recoverInterior, else empty
  // ||K_FF u_F - f_F|| / ||f_F||. For a kept-only DenseResponse solve it is the largest relative
  // residual of the precomputed response columns (a bound that holds for every edit).
  double relativeResidual = 0.0;
  bool residualIsBound = false;
  SolveMethod method = SolveMethod::FullReference;
  std::string backend;
  StageTimings timings; // precompute stages marked reused, plus this solve's own stages
};

// May be called from several worker threads at once (make it thread-safe, e.g. an atomic store).
using ProgressCallback = std::function<void(double fraction, const char* what)>;

// Everything the precompute produced. Immutable once built, so solves may share it across threads.
class CondensedSystem;

struct PrecomputeRequest {
  TetMesh mesh;
  Materials materials;
  NodeSets sets;
  PrecomputeOptions options;
};

// Builds the cached system. `cancel` is polled between stages and response blocks; a cancelled
// precompute returns an error status "cancelled".
Status Precompute(const PrecomputeRequest& request, std::shared_ptr<const CondensedSystem>& system,
                  const std::atomic<bool>* cancel = nullptr, const ProgressCallback& progress = {});

// Solves for one set of prescribed values and loads with the cached system.
Status Solve(const CondensedSystem& system, const SolveInput& input, SolveResult& result);

// The paper's "traditional FEM": no condensation and no cache, the whole free system is assembled,
// factored and solved from scratch. Used for verification and comparison.
Status SolveFullReference(const PrecomputeRequest& request, const SolveInput& input,
                          SolveResult& result);

// What a precompute chose and how big it is (for reports and the ParaView stage table).
struct SystemInfo {
  SolveMethod method = SolveMethod::Auto;
  std::string backend;
  long long freeDofs = 0, keptDofs = 0, roiDofs = 0, interiorDofs = 0;
  double factorNonzeros = 0.0;
  double responseBytes = 0.0;
  std::string choiceReason;
  StageTimings precomputeTimings;
};
SystemInfo Describe(const CondensedSystem& system);

} // namespace faceplan
