// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Linear static FEM on tetrahedra with interior condensation, split libigl-style into a precompute
// (mesh, materials, node sets) and a solve (prescribed ROI displacements and loads).
//
// Node classes: constrained (tied to bone), of which the `movable` subset (the ROI) receives
// prescribed displacements and the rest stay at zero; kept (the caller needs their displacement,
// typically the skin); interior (everything else, condensed out). Because only ROI DOFs ever carry
// prescribed values, an edit needs nothing but the response of the kept DOFs to the ROI DOFs.
// Sliding nodes (NodeSets::sliding) are constrained along their normal only: their DOFs are
// rotated into the normal frame (K' = Q^T K Q on their blocks), the normal DOF is prescribed and
// the tangential ones are free, so the same precompute/solve split holds.
#include "Backend/ComputeBackend.h"
#include "Common/StageTimings.h"
#include "Common/Status.h"
#include "CondensedFEM/RigidSegments.h"
#include "Element/QuadraticTet.h"
#include "Mesh/NodeSets.h"
#include "Mesh/TetMesh.h"

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace faceplan {

enum class SolveMethod {
  Auto,          // pick the cheapest exact method from the sizes (see ChooseMethod)
  DenseResponse, // precompute kept x ROI response; an edit is one matrix-vector product
  CachedFactor,  // keep the sparse Cholesky factor of the free block; an edit is one solve
  FullReference, // no condensation, no cache: assemble and factor everything on every solve
  RigidSegments, // precompute the kept response to 12 affine motions per rigid segment (plus the
                 // general response to the ROI DOFs of segment-0 nodes); an edit is one product
                 // with the 12 parameters per segment and the general part. Auto picks it when
                 // NodeSets::movableSegment names segments and the response fits the budget.
  // The neo-Hookean model's results (LargeDeformation.h, PrecomputedLargeDeformation.h): Newton's
  // method with a factorization per iteration, and the solve with the precomputed factor. Never
  // chosen by Auto, and not a precompute's method.
  LargeDeformationNewton,
  LargeDeformationPrecomputed
};
const char* MethodName(SolveMethod method);

// Element type. Linear 4-node tetrahedra lock (are too stiff) as the Poisson ratio approaches 0.5;
// Quadratic converts the caller's linear mesh to 10-node tetrahedra internally (mid-edge nodes
// follow their edge's end nodes into the node sets: constrained when both ends are, with the mean
// of the ends' prescribed values; movable when both ends are constrained and one is movable;
// otherwise interior) and reports results at the original corner nodes, so inputs and outputs keep
// the linear mesh's numbering. See docs/STABILITY.md for when to use it and its cost.
// QuadraticNodalPressure: the same 10-node cells, but the volumetric (lambda) term uses a
// continuous pressure on the corner nodes with a lumped pressure mass (P2-P1, NodalPressure.h):
// exact and symmetric, its error does not grow as nu -> 0.5, but its wider stencil makes the
// factor and the precompute several times larger than Quadratic's (BENCHMARKS.md).
enum class ElementOrder { Linear, Quadratic, QuadraticNodalPressure };
const char* ElementOrderName(ElementOrder order);

struct PrecomputeOptions {
  SolveMethod method = SolveMethod::Auto;
  // Largest dense response Auto may build, in bytes.
  double denseResponseBudgetBytes = 2.0e9;
  // Memory the precompute may use for the sparse factor and the dense response, in bytes; 0 takes
  // the available memory (MemAvailable in /proc/meminfo) when the precompute starts. Checked after
  // the symbolic analysis, before either is allocated: a factor over the budget is an error; a
  // dense response that does not fit beside the factor makes Auto keep the factor instead, and is
  // an error when DenseResponse was requested.
  double memoryBudgetBytes = 0.0;
  // Compute backend for element stiffness, assembly and the dense per-edit update; null = CPU.
  std::shared_ptr<ComputeBackend> backend;
  // Columns of the response solved per block (bounds the precompute's transient memory): large
  // enough that the solve's gathered rows stay in cache, small enough to keep the transient memory
  // at half of what 256 columns take (BENCHMARKS.md, "Figures behind design choices in Core").
  int responseBlockColumns = 128;

  // Element order and stability options (all optional; the defaults are linear elements).
  ElementOrder elementOrder = ElementOrder::Linear;
  // Quadratic only: places the mid-edge node of a boundary edge (curved boundaries); empty keeps
  // the straight midpoint. Called during the precompute, on the calling thread.
  MidEdgeProjection midEdgeProjection;
  // Quadratic only: integrate the volumetric term with the cell's mean dilatation (P2-P0 mixed
  // element, exact and symmetric; see Tet10Stiffness). Off gives the plain fully integrated TET10,
  // which still locks noticeably for nu >= 0.499.
  bool quadraticMeanDilatation = true;
  // Cells with mean-ratio quality below this give a warning (count and worst quality); 0 disables.
  double sliverQualityThreshold = 0.02;
  // Largest relative residual a solve accepts before it refines the solution in double precision
  // (iterative refinement with the cached factor, up to maxRefinementSteps extra solves).
  double residualTolerance = 1e-10;
  int maxRefinementSteps = 3;
  // A backend's per-edit response operator (which may compute in single precision) is probed
  // against the double response after the precompute; when its relative deviation exceeds this,
  // edits are redone in double on the CPU and the diagnostics say so.
  double responseTolerance = 1e-9;
  // Strain above which a solve warns that linear FEM is outside its range (0 disables the check,
  // which also skips the inverted-cell check).
  double strainWarningLimit = 0.1;
};

struct SolveInput {
  // |movable| x 3, in NodeSets::movable order. Sliding nodes use only its normal part.
  RowVectors3d movableDisplacement;
  // One [R | t] per rigid segment (segment k uses entry k - 1), or empty. The displacements above
  // remain the boundary values of every path; when transforms are given and the system has
  // segments, Solve checks that the segments' displacements follow them (CheckSegmentDisplacements)
  // and RigidSegments takes its parameters from them. RigidSegments requires them; a system
  // without segments ignores them.
  std::vector<SegmentTransform> segmentTransforms;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero(); // body load density * gravity, if non-zero
  RowVectors3d nodalLoads;                           // n x 3 or empty
  bool recoverInterior = false;                      // also return every node's displacement
};

struct SolveResult {
  RowVectors3d keptDisplacement; // |kept| x 3, in NodeSets::kept order
  RowVectors3d allDisplacement;  // n x 3 when recoverInterior, else empty
  // ||K_FF u_F - f_F|| / ||f_F||. For a kept-only DenseResponse solve it is the precompute's figure
  // for the response (SystemInfo::responsePath says which): an estimate from random combinations
  // of its columns, or the largest relative residual of its columns when it needed refinement.
  double relativeResidual = 0.0;
  bool residualFromPrecompute = false; // relativeResidual is the precompute's, not this solve's
  SolveMethod method = SolveMethod::FullReference;
  std::string backend;
  StageTimings timings; // precompute stages marked reused, plus this solve's own stages

  // Diagnostics.
  double conditionEstimate = 0.0; // 1 / CHOLMOD rcond of the free block (a cheap lower estimate)
  int refinementSteps = 0;        // double-precision refinement steps this solve needed
  bool redoneInDouble = false;    // a lower-precision response missed the tolerance; done in double
  std::string precisionNote;      // how the per-edit product was computed when not plain double
  double largestStrain = 0.0;     // over the cells the solve could check (see CheckDeformation)
  long long invertedCells = 0;    // cells inverted in the deformed result
  ElementOrder elementOrder = ElementOrder::Linear;
  std::vector<std::string> warnings; // the same as the returned Status's warnings
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
// Linear cells only: request.options (elementOrder included) are not used.
Status SolveFullReference(const PrecomputeRequest& request, const SolveInput& input,
                          SolveResult& result);

// What a precompute chose and how big it is (for reports and the ParaView stage table).
struct SystemInfo {
  SolveMethod method = SolveMethod::Auto;
  std::string backend;
  long long freeDofs = 0, keptDofs = 0, roiDofs = 0, interiorDofs = 0;
  double factorNonzeros = 0.0;
  double factorBytes = 0.0; // the numeric factor's estimated size (from the symbolic analysis)
  double responseBytes = 0.0;
  double memoryBudgetBytes = 0.0; // the budget the precompute was checked against
  std::string choiceReason;
  std::string ordering; // fill-reducing ordering of the free block ("METIS", "AMD", ...)
  bool orderedBesideAssembly = false; // made from the node graph while the assembly ran
  // Threads beside the assembly: their own run times. The stage rows hold only the waits for
  // them, so that the rows add up to the precompute's time.
  double orderingThreadMs = 0.0;   // Reordering (0 when it ran in line: its row is its time)
  double meshChecksThreadMs = 0.0; // shared-face checks: held rigid modes, quality, folds
  std::string responsePath; // how the dense response was computed and checked (DenseResponse)
  StageTimings precomputeTimings;

  // Diagnostics.
  double conditionEstimate = 0.0; // 1 / CHOLMOD rcond of the free block (0 when there is none)
  ElementOrder elementOrder = ElementOrder::Linear;
  long long solverNodes = 0; // nodes of the solved mesh (corners + mid-edge nodes if quadratic)
  long long sliverCells = 0; // cells below sliverQualityThreshold
  long long foldedFaces = 0; // shared faces whose two cells overlap (CheckFoldedFaces)
  double worstQuality = 1.0; // smallest mean-ratio quality
  double responseProbeError = 0.0;       // relative deviation of the backend's response operator
  double responseProbeRowFraction = 1.0; // share of the response's rows that probe compared
  double responseProbeMs = 0.0;          // the probe's time (inside the Condensation row)
  double conditionEstimateMs = 0.0; // cholmod_rcond on the factor (inside the Factorization row)
  bool responseRedoneInDouble = false;
  std::vector<std::string> warnings; // the precompute's warnings
};
SystemInfo Describe(const CondensedSystem& system);

} // namespace faceplan
