#include "CondensedFEM/CondensedFEM.h"

#include "Common/BlasThreads.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Element/ElementStiffness.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "Mesh/MeshValidation.h"
#include "Element/NodalPressure.h"
#include "Mesh/NodeSetValidation.h"
#include "SparseSolver/TrailingResponse.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <thread>

namespace faceplan {

const char* MethodName(SolveMethod method) {
  switch (method) {
  case SolveMethod::Auto: return "Auto";
  case SolveMethod::DenseResponse: return "DenseResponse";
  case SolveMethod::CachedFactor: return "CachedFactor";
  case SolveMethod::FullReference: return "FullReference";
  }
  return "?";
}

const char* ElementOrderName(ElementOrder order) {
  switch (order) {
  case ElementOrder::Linear: return "Linear";
  case ElementOrder::Quadratic: return "Quadratic";
  case ElementOrder::QuadraticNodalPressure: return "QuadraticNodalPressure";
  }
  return "?";
}

namespace {

// Lumped rho * V / 4 per free node: the consistent gravity load of a linear tetrahedron.
Eigen::VectorXd FreeNodeMass(const TetMesh& mesh, const Materials& materials, const NodeLayout& layout) {
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(layout.freeNodes());
  if (materials.density.size() == 0) return mass;
  TetCorners corners;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    const double rho = materials.rho(e);
    if (rho == 0.0) continue;
    for (int k = 0; k < 4; ++k) corners.row(k) = mesh.points.row(mesh.tets(e, k));
    const double quarter = rho * TetVolume(corners) / 4.0;
    for (int k = 0; k < 4; ++k) {
      const int pos = layout.dofNode[mesh.tets(e, k)];
      if (pos >= 0 && pos < layout.freeNodes()) mass[pos] += quarter;
    }
  }
  return mass;
}

// Consistent unit-body-force load per free node of a quadratic mesh (integral of rho N_a).
Eigen::VectorXd FreeNodeMassQuadratic(const QuadraticMesh& mesh, const Materials& materials,
                                      const NodeLayout& layout) {
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(layout.freeNodes());
  if (materials.density.size() == 0) return mass;
  Tet10Nodes nodes;
  for (Eigen::Index e = 0; e < mesh.cells.rows(); ++e) {
    const double rho = materials.rho(e);
    if (rho == 0.0) continue;
    for (int k = 0; k < 10; ++k) nodes.row(k) = mesh.points.row(mesh.cells(e, k));
    const Eigen::Matrix<double, 10, 1> integral = Tet10ShapeIntegrals(nodes);
    for (int k = 0; k < 10; ++k) {
      const int pos = layout.dofNode[mesh.cells(e, k)];
      if (pos >= 0 && pos < layout.freeNodes()) mass[pos] += rho * integral[k];
    }
  }
  return mass;
}

// x = K_FF^-1 b with double-precision iterative refinement: while a column's relative residual
// exceeds `tolerance`, solve for the residual and correct (at most `maxSteps` times). `worst`
// receives the largest relative residual after refinement and `steps` the refinement steps taken.
// `fullRowMajor`, when given, is K_FF with both triangles in row-major storage: a product with
// many right-hand sides then streams each row once (about 2.5x faster than the symmetric view).
using RowMajorSparse = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using RowMajorDense = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// `initial`, when given, is used as the first solution instead of solving for b.
Status RefinedSolve(const CondensedSystem& sys, const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                    bool concurrent, double tolerance, int maxSteps, double& worst, int& steps,
                    const RowMajorSparse* fullRowMajor = nullptr,
                    const Eigen::MatrixXd* initial = nullptr) {
  auto solve = [&](const Eigen::MatrixXd& rhs, Eigen::MatrixXd& out) {
    return concurrent ? sys.factor.solveConcurrently(rhs, out) : sys.factor.solve(rhs, out);
  };
  Status s = Status::Ok();
  if (initial)
    x = *initial;
  else
    s = solve(b, x);
  if (!s) return s;
  const Eigen::VectorXd norms = b.colwise().norm().transpose();
  steps = 0;
  for (;;) {
    Eigen::MatrixXd residual;
    if (fullRowMajor && b.cols() > 1) {
      const RowMajorDense xr = x;
      residual = b - Eigen::MatrixXd(RowMajorDense(*fullRowMajor * xr));
    } else {
      residual = b - sys.kff.selfadjointView<Eigen::Upper>() * x;
    }
    worst = 0.0;
    for (Eigen::Index c = 0; c < b.cols(); ++c) {
      const double r = residual.col(c).norm();
      worst = std::max(worst, norms[c] > 0.0 ? r / norms[c] : r);
    }
    if (!std::isfinite(worst) || worst <= tolerance || steps >= maxSteps) break;
    Eigen::MatrixXd correction;
    s = solve(residual, correction);
    if (!s) return s;
    x += correction;
    ++steps;
  }
  return Status::Ok();
}

// The free DOFs' response to `load` (K_FF^-1 load, refined), solved when the load differs from
// the last one and reused while it does not. `residual` and `steps` are that solve's (0 if reused).
Status CachedLoadResponse(const CondensedSystem& sys, const Eigen::VectorXd& load,
                          Eigen::VectorXd& response, double& residual, int& steps) {
  std::lock_guard<std::mutex> lock(sys.loadMutex);
  residual = 0.0;
  steps = 0;
  if (sys.lastLoad.size() != load.size() || sys.lastLoad != load) {
    Eigen::MatrixXd x;
    Status s = RefinedSolve(sys, load, x, false, sys.residualTolerance, sys.maxRefinementSteps,
                            residual, steps);
    if (!s)
      return s;
    sys.lastLoad = load;
    sys.lastLoadResponse = x.col(0);
  }
  response = sys.lastLoadResponse;
  return Status::Ok();
}

// The caller's node sets extended to the mid-edge nodes of a quadratic mesh. `derived` receives,
// for each mid-edge ROI node (appended after the caller's movable nodes), its ends' positions in
// the caller's movable list (-1 for a fixed end).
NodeSets QuadraticNodeSets(const QuadraticMesh& q, const NodeSets& sets,
                           std::vector<std::array<int, 2>>& derived) {
  const Eigen::Index n = q.numCorners;
  std::vector<char> constrained(n, 0);
  std::vector<int> movablePos(n, -1);
  for (int i : sets.constrained) constrained[i] = 1;
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (movablePos[sets.movable[k]] < 0) movablePos[sets.movable[k]] = static_cast<int>(k);
  NodeSets out = sets;
  derived.clear();
  for (size_t e = 0; e < q.edges.size(); ++e) {
    const int a = q.edges[e][0], b = q.edges[e][1];
    if (!constrained[a] || !constrained[b]) continue; // interior: kept nodes are corners only
    const int node = static_cast<int>(n + static_cast<Eigen::Index>(e));
    out.constrained.push_back(node);
    if (movablePos[a] >= 0 || movablePos[b] >= 0) {
      out.movable.push_back(node);
      derived.push_back({movablePos[a], movablePos[b]});
    }
  }
  return out;
}

// Relative deviation of a backend's response operator from the double response, on random ROI
// vectors (a float operator shows ~1e-7; a double one ~1e-16).
double ProbeResponseOperator(const CondensedSystem& sys, ResponseOperator& op, std::string& error) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  double worst = 0.0;
  for (int probe = 0; probe < 2; ++probe) {
    Eigen::VectorXd roi(sys.response.cols());
    for (Eigen::Index k = 0; k < roi.size(); ++k) roi[k] = uniform(rng);
    Eigen::VectorXd approx;
    if (!op.apply(roi, approx, error)) return std::numeric_limits<double>::infinity();
    const Eigen::VectorXd exact = sys.response * roi;
    if (approx.size() != exact.size()) {
      error = "operator returned the wrong size";
      return std::numeric_limits<double>::infinity();
    }
    const double norm = exact.norm();
    const double dev = (approx - exact).norm();
    worst = std::max(worst, norm > 0.0 ? dev / norm : dev);
  }
  return worst;
}

// Per-edit cost decides between a dense product and a sparse solve (both exact). A sparse
// triangular solve runs at about a third of a dense product's flop rate (scripts/report measured
// 3.3 against 1.1 GFLOP/s median over its scenes), so its flops are weighted by that ratio.
constexpr double kSparseSolveFlopWeight = 3.0;
// Flops of one solve with the factor for a right-hand side on the ROI-coupled DOFs: a backward
// substitution plus the trailing block's dense forward one when those DOFs were ordered last
// (trailingDofs > 0), else both full substitutions.
double FactorSolveFlops(double factorNonzeros, double trailingDofs) {
  return trailingDofs > 0 ? 2.0 * factorNonzeros + trailingDofs * trailingDofs
                          : 4.0 * factorNonzeros;
}
SolveMethod ChooseMethod(const PrecomputeOptions& options, double keptDofs, double roiDofs,
                         double factorNonzeros, double trailingDofs, std::string& reason) {
  const double denseBytes = 8.0 * keptDofs * roiDofs;
  const double denseFlops = 2.0 * keptDofs * roiDofs;
  const double factorFlops =
      FactorSolveFlops(factorNonzeros, trailingDofs) * kSparseSolveFlopWeight;
  std::ostringstream why;
  why.precision(3);
  if (options.method == SolveMethod::DenseResponse || options.method == SolveMethod::CachedFactor) {
    why << "requested";
    reason = why.str();
    return options.method;
  }
  if (roiDofs == 0 || keptDofs == 0) {
    reason = "nothing moves or nothing is kept: a cached factor serves loads alone";
    return SolveMethod::CachedFactor;
  }
  if (denseBytes > options.denseResponseBudgetBytes) {
    why << "dense response would take " << denseBytes / 1e6 << " MB, over the "
        << options.denseResponseBudgetBytes / 1e6 << " MB budget";
    reason = why.str();
    return SolveMethod::CachedFactor;
  }
  if (denseFlops < factorFlops) {
    why << "an edit costs " << denseFlops / 1e6 << " MFLOP as a dense product against "
        << factorFlops / 1e6 << " dense-equivalent MFLOP as a factor solve";
    reason = why.str();
    return SolveMethod::DenseResponse;
  }
  why << "a factor solve (" << factorFlops / 1e6
      << " dense-equivalent MFLOP) is cheaper than the dense product ("
      << denseFlops / 1e6 << " MFLOP)";
  reason = why.str();
  return SolveMethod::CachedFactor;
}

// Columns of the response, solved in blocks: one single-threaded solve per core at a time, each
// with its own CHOLMOD workspace, blocks sized so the transient memory stays near 1 GB.
// First the cheap path (backward substitutions from the trailing block, residual estimated by
// random probes; TrailingResponse.h); when it is unavailable or its estimate misses the tolerance,
// full solves with a residual and iterative refinement per column.
Status BuildResponse(CondensedSystem& sys, const PrecomputeOptions& options,
                     const std::atomic<bool>* cancel, const ProgressCallback& progress) {
  const Eigen::Index keptDofs = 3 * sys.layout.keptFree, roiDofs = sys.kfr.cols();
  const Eigen::Index freeDofs = sys.kff.rows();
  const int threads = static_cast<int>(std::max(1u, std::min(std::thread::hardware_concurrency(), 16u)));
  const double bytesPerColumn = 8.0 * 5.0 * double(std::max<Eigen::Index>(freeDofs, 1));
  const Eigen::Index memoryBlock = static_cast<Eigen::Index>(1.0e9 / (bytesPerColumn * threads));
  const Eigen::Index largestBlock = std::clamp<Eigen::Index>(std::min<Eigen::Index>(memoryBlock, options.responseBlockColumns), 8,
                                                      std::max(8, options.responseBlockColumns));
  if (sys.factor.trailingDofs() > 0) {
    TrailingResponseResult fast;
    Status fs = BuildTrailingResponse(
        sys.factor, sys.kff, sys.kfr, keptDofs, largestBlock, cancel,
        [&progress](double f) {
          if (progress)
            progress(0.6 + 0.4 * f, "dense response");
        },
        fast);
    if (!fs)
      return fs;
    std::ostringstream how;
    how.precision(3);
    if (fast.residualEstimate <= sys.residualTolerance) {
      sys.response = std::move(fast.response);
      sys.responseResidual = fast.residualEstimate;
      how << "backward substitutions from the ROI-coupled trailing block; relative residual "
          << fast.residualEstimate << " estimated with " << fast.probes << " random probes";
      sys.info.responsePath = how.str();
      return Status::Ok();
    }
    how << "full solves with per-column residuals and refinement (the probe estimate "
        << fast.residualEstimate << " of the backward-substitution response missed "
        << sys.residualTolerance << ")";
    sys.info.responsePath = how.str();
  } else {
    sys.info.responsePath = "full solves with per-column residuals and refinement";
  }
  sys.response.resize(keptDofs, roiDofs);
  const Eigen::Index evenShare = (roiDofs + threads - 1) / threads; // keep every core busy
  const Eigen::Index block = std::max<Eigen::Index>(1, std::min(largestBlock, evenShare));
  const Eigen::Index blocks = (roiDofs + block - 1) / block;

  ScopedBlasThreads singleThreadedBlas(1);
  const RowMajorSparse kffFull = sys.kff.selfadjointView<Eigen::Upper>(); // for the residuals
  std::atomic<Eigen::Index> nextBlock{0}, doneBlocks{0};
  std::mutex resultMutex;
  Status failure = Status::Ok();
  double worst = 0.0;
  auto worker = [&] {
    for (Eigen::Index b = nextBlock++; b < blocks; b = nextBlock++) {
      if (cancel && cancel->load()) return;
      const Eigen::Index c0 = b * block, cols = std::min(block, roiDofs - c0);
      const Eigen::MatrixXd rhs = Eigen::MatrixXd(sys.kfr.middleCols(c0, cols));
      Eigen::MatrixXd x;
      double blockWorst = 0.0;
      int steps = 0;
      Status s = RefinedSolve(sys, rhs, x, true, sys.residualTolerance, sys.maxRefinementSteps,
                              blockWorst, steps, &kffFull);
      if (!s) {
        std::lock_guard<std::mutex> lock(resultMutex);
        failure = s;
        return;
      }
      sys.response.middleCols(c0, cols) = -x.topRows(keptDofs); // disjoint columns per block
      std::lock_guard<std::mutex> lock(resultMutex);
      worst = std::max(worst, blockWorst);
      ++doneBlocks;
      if (progress) progress(0.6 + 0.4 * double(doneBlocks.load()) / double(blocks), "dense response");
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<Eigen::Index>(threads, blocks); ++t) pool.emplace_back(worker);
  worker(); // the calling thread works too
  for (auto& th : pool) th.join();
  if (progress) progress(1.0, "dense response");
  if (cancel && cancel->load()) return Status::Error("cancelled");
  if (!failure) return failure;
  sys.responseResidual = worst;
  return Status::Ok();
}

Status PrecomputeImpl(const PrecomputeRequest& request, std::shared_ptr<const CondensedSystem>& out,
                      const std::atomic<bool>* cancel, const ProgressCallback& progress) {
  auto cancelled = [cancel] { return cancel && cancel->load(); };
  auto report = [&progress](double f, const char* what) {
    if (progress) progress(f, what);
  };
  const TetMesh& mesh = request.mesh;
  const PrecomputeOptions& options = request.options;
  if (options.method == SolveMethod::FullReference)
    return Status::Error("FullReference has no precompute: call SolveFullReference");

  StageClock total, clock;
  auto sys = std::make_shared<CondensedSystem>();
  StageTimings& t = sys->info.precomputeTimings;
  Status status = ValidateMeshAndMaterials(mesh, request.materials);
  if (status) status = ValidateNodeSets(mesh, request.sets);
  if (status) status = CheckEveryComponentConstrained(mesh, request.sets.constrained);
  if (status) status = CheckRigidModesHeld(mesh, request.sets.constrained);
  if (!status) return status;
  if (!(options.residualTolerance > 0.0) || options.maxRefinementSteps < 0)
    return Status::Error("residualTolerance must be positive and maxRefinementSteps non-negative");
  SystemInfo& info = sys->info;
  if (options.sliverQualityThreshold > 0.0) {
    QualityReport quality;
    const std::string w = CheckElementQuality(mesh, options.sliverQualityThreshold, &quality);
    if (!w.empty()) status.warnings.push_back(w);
    info.sliverCells = quality.belowThreshold;
    info.worstQuality = quality.worstQuality;
  }
  sys->residualTolerance = options.residualTolerance;
  sys->maxRefinementSteps = options.maxRefinementSteps;
  sys->strainWarningLimit = options.strainWarningLimit;
  sys->numOutputNodes = mesh.numPoints();
  sys->cornerMesh = mesh;
  sys->kept = request.sets.kept;
  sys->movableNodes = request.sets.movable;
  const bool quadratic = options.elementOrder == ElementOrder::Quadratic ||
                         options.elementOrder == ElementOrder::QuadraticNodalPressure;
  const bool nodalPressure = options.elementOrder == ElementOrder::QuadraticNodalPressure;
  // Nodal pressure: cells give the shear part; the volumetric part is added after assembly.
  const Materials cellMaterials = nodalPressure ? ShearOnlyMaterials(request.materials) : Materials();
  const Materials& stiffnessMaterials = nodalPressure ? cellMaterials : request.materials;
  info.elementOrder = options.elementOrder;

  // Quadratic elements: the TET10 mesh and the node sets extended to its mid-edge nodes.
  QuadraticMesh qmesh;
  NodeSets solverSets;
  if (quadratic) {
    qmesh = MakeQuadraticMesh(mesh, options.midEdgeProjection);
    if (!qmesh.points.allFinite())
      return Status::Error("the mid-edge projection returned non-finite coordinates");
    solverSets = QuadraticNodeSets(qmesh, request.sets, sys->derivedMovable);
  }
  const NodeSets& sets = quadratic ? solverSets : request.sets;
  sys->numMeshNodes = quadratic ? qmesh.points.rows() : mesh.numPoints();
  info.solverNodes = sys->numMeshNodes;
  {
    std::vector<char> used(sys->numMeshNodes, 0);
    if (quadratic) {
      for (Eigen::Index k = 0; k < qmesh.cells.size(); ++k) used[qmesh.cells.data()[k]] = 1;
    } else {
      for (Eigen::Index k = 0; k < mesh.tets.size(); ++k) used[mesh.tets.data()[k]] = 1;
    }
    sys->layout = MakeLayout(used, sets);
  }
  const NodeLayout& layout = sys->layout;
  {
    // Cells a kept-only solve can check for large strain: every corner kept or constrained.
    std::vector<char> known(mesh.numPoints(), 0);
    for (int i : request.sets.kept) known[i] = 1;
    for (int i : request.sets.constrained) known[i] = 1;
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
      if (known[mesh.tets(e, 0)] && known[mesh.tets(e, 1)] && known[mesh.tets(e, 2)] && known[mesh.tets(e, 3)])
        sys->checkableCells.push_back(static_cast<int>(e));
  }
  t[Stage::Separation].ms = clock.lapMs();
  report(0.05, "separation");
  if (cancelled()) return Status::Error("cancelled");

  AssemblyPattern pattern =
      quadratic ? BuildCellAssemblyPattern(qmesh.cells.data(), qmesh.cells.rows(), 10, layout.dofNode,
                                           static_cast<int>(layout.meshNode.size()))
                : BuildAssemblyPattern(mesh, layout.dofNode, static_cast<int>(layout.meshNode.size()));
  const double patternMs = clock.lapMs();
  std::shared_ptr<ComputeBackend> backend = options.backend ? options.backend : MakeCpuBackend();
  ComputeBackend::AssemblyTimings at;
  std::string error;
  if (quadratic) {
    // The backends implement 4-node cells; 10-node cells are computed and assembled on the CPU.
    std::vector<double> packed;
    std::vector<long long> invalid;
    ComputePackedTet10Stiffness(qmesh, stiffnessMaterials, packed, invalid, options.quadraticMeanDilatation);
    if (!invalid.empty()) {
      std::ostringstream msg;
      msg << invalid.size() << " quadratic cells have a non-positive Jacobian after the mid-edge "
          << "projection (first: cell " << invalid.front()
          << "); the projection moves mid-edge nodes too far for these cells";
      return Status::Error(msg.str());
    }
    at.elementStiffnessMs = clock.lapMs();
    AssembleFromPacked(packed, pattern);
    at.assemblyMs = clock.lapMs();
  } else if (!backend->assembleStiffness(mesh, request.materials, pattern, at, error)) {
    status.warnings.push_back(backend->name() + " backend failed (" + error + "); used the CPU");
    backend = MakeCpuBackend();
    at = {};
    backend->assembleStiffness(mesh, request.materials, pattern, at, error);
  }
  if (nodalPressure) { // the volumetric part, added to the shear part assembled above
    clock.lapMs();
    AddNodalPressureStiffness(pattern.upper, qmesh.points, qmesh.cells.data(), qmesh.cells.rows(), 10,
                              request.materials, layout.dofNode, static_cast<int>(layout.meshNode.size()));
    at.assemblyMs += clock.lapMs();
  }
  sys->backendName = backend->name();
  t[Stage::ElementStiffness].ms = at.elementStiffnessMs;
  t[Stage::Assembly].ms = patternMs + at.assemblyMs;
  clock.lapMs();
  report(0.15, "assembly");
  if (cancelled()) return Status::Error("cancelled");

  // Blocks of the assembled upper triangle: free columns first, then ROI columns.
  const int freeDofs = 3 * layout.freeNodes();
  const SparseMatrix& upper = pattern.upper;
  sys->kff = Eigen::Map<const SparseMatrix>(freeDofs, freeDofs, upper.outerIndexPtr()[freeDofs],
                                            upper.outerIndexPtr(), upper.innerIndexPtr(),
                                            upper.valuePtr());
  sys->kfr = upper.block(0, freeDofs, freeDofs, upper.cols() - freeDofs);
  sys->kfr.makeCompressed();
  { AssemblyPattern().upper.swap(pattern.upper); } // free the global pattern early
  pattern = AssemblyPattern();
  sys->nodeMass = quadratic ? FreeNodeMassQuadratic(qmesh, request.materials, layout)
                            : FreeNodeMass(mesh, request.materials, layout);
  qmesh = QuadraticMesh();
  t[Stage::Separation].ms += clock.lapMs();

  info.backend = sys->backendName;
  info.freeDofs = freeDofs;
  info.keptDofs = 3LL * layout.keptFree;
  info.roiDofs = 3LL * layout.roi;
  info.interiorDofs = 3LL * layout.interior;

  if (freeDofs > 0) {
    // METIS on the node graph with the ROI-coupled nodes last (FillReducingOrdering.h). That
    // halves a response solve but makes those nodes a dense block of the factor, which does not
    // pay when the ROI is large; then the ordering without it is analysed too and the one with
    // the lower estimated precompute is kept: factorization flops plus one solve per ROI DOF
    // (forward + backward, or backward + the trailing block). CHOLMOD's own choice if neither
    // ordering can be made.
    const double roiColumns = double(sys->kfr.cols());
    auto estimatedCost = [roiColumns](double nonzeros, double flops, int trailing) {
      return flops + roiColumns * FactorSolveFlops(nonzeros, trailing);
    };
    std::vector<FillReducingOrdering> candidates;
    bool settled = false;
    FillReducingOrdering trailingLast;
    if (sys->kfr.cols() > 0 &&
        OrderNodesWithTrailing(sys->kff, 3, NodesCoupledTo(sys->kfr, layout.freeNodes(), 3),
                               trailingLast)
            .ok) {
      candidates.push_back(std::move(trailingLast));
      Status as = sys->factor.analyze(sys->kff, candidates, estimatedCost);
      if (!as)
        return as;
      // Settled without the other ordering when even losing the whole trailing block (t^3/3
      // flops, t^2/2 entries) could not make full solves cheaper: t^3/3 + 3 r t^2 <= 2 r nnz(L).
      const double block = sys->factor.trailingDofs(), r = roiColumns;
      settled = block > 0 && block * block * block / 3.0 + 3.0 * r * block * block <=
                                 2.0 * r * sys->factor.factorNonzeros();
    }
    if (!settled) {
      // Both candidates analysed together (the trailing one a second time: CholmodFactor keeps
      // one analysis; this only happens for ROIs large enough to doubt the trailing block).
      FillReducingOrdering plain;
      if (OrderNodesWithTrailing(sys->kff, 3, {}, plain).ok)
        candidates.push_back(std::move(plain));
      Status as = sys->factor.analyze(sys->kff, candidates, estimatedCost);
      if (!as)
        return as; // (not into `status`: that would drop its warnings)
    }
    info.ordering = candidates.empty()
                        ? "CHOLMOD default"
                        : std::string(candidates.front().method) +
                              (sys->factor.trailingDofs() > 0 ? ", ROI-coupled DOFs last" : "");
    t[Stage::Reordering].ms = clock.lapMs();
    info.factorNonzeros = sys->factor.factorNonzeros();
    report(0.25, "reordering");
    if (cancelled()) return Status::Error("cancelled");
  }
  // The method needs only the analysis (the factor's size), so it is chosen before the numeric
  // factorization, which a backend may then do together with the response.
  sys->method =
      ChooseMethod(options, double(info.keptDofs), double(info.roiDofs), info.factorNonzeros,
                   double(sys->factor.trailingDofs()), info.choiceReason);
  if (freeDofs == 0) sys->method = SolveMethod::CachedFactor;
  info.method = sys->method;

  // Backend factorization + response (CUDA: numeric factorization and dense response on the GPU).
  // Whatever it does not deliver is done on the CPU below, with a warning.
  bool backendResponse = false;
  std::unique_ptr<ResponseOperator> backendOperator;
  if (freeDofs > 0 && sys->method == SolveMethod::DenseResponse && backend->providesFactorAndResponse()) {
    ComputeBackend::FactorResponseReport fr;
    std::string hookError;
    bool ok = backend->factorAndBuildResponse(sys->kff, sys->kfr, 3 * layout.keptFree, sys->factor,
                                              sys->response, backendOperator, fr, hookError);
    const bool factored = sys->factor.isFactorized();
    if (ok && !(fr.worstRelativeResidual <= sys->residualTolerance)) {
      std::ostringstream why;
      why << "its response's relative residual " << fr.worstRelativeResidual << " exceeds "
          << sys->residualTolerance;
      hookError = why.str();
      ok = false;
    }
    const double hookMs = clock.lapMs();
    const double factorMs = factored ? std::min(fr.factorizationMs, hookMs) : hookMs;
    t[Stage::Factorization].ms += factorMs;
    t[Stage::Condensation].ms += hookMs - factorMs;
    if (ok && factored && sys->response.rows() == info.keptDofs && sys->response.cols() == info.roiDofs) {
      backendResponse = true;
      sys->responseResidual = fr.worstRelativeResidual;
      report(0.95, "dense response");
    } else {
      if (ok) hookError = "internal: the response or the factor is missing";
      status.warnings.push_back(backend->name() + " factorization/response failed (" + hookError + "); " +
                                (factored ? "the response was built" : "factorized and built the response") +
                                " on the CPU");
      sys->response.resize(0, 0);
      backendOperator.reset();
    }
  }
  if (freeDofs > 0) {
    if (!sys->factor.isFactorized()) {
      Status fs = sys->factor.factorize(sys->kff);
      if (!fs) return fs;
      t[Stage::Factorization].ms += clock.lapMs();
    }
    const double rcond = sys->factor.reciprocalConditionEstimate();
    info.conditionEstimate = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
    if (!backendResponse) report(0.6, "factorization");
  }

  if (sys->method == SolveMethod::DenseResponse) {
    if (!backendResponse) {
      Status rs = BuildResponse(*sys, options, cancel, progress);
      if (!rs) return rs;
    }
    info.responseBytes = 8.0 * double(sys->response.size());
    sys->responseOperator = backendOperator ? std::move(backendOperator)
                                            : backend->makeResponseOperator(sys->response, error);
    if (!sys->responseOperator) {
      status.warnings.push_back(backend->name() + " could not hold the response (" + error +
                                "); edits run on the CPU");
      sys->responseOperator = MakeCpuBackend()->makeResponseOperator(sys->response, error);
    } else if (options.backend) {
      // A backend may hold the response in lower precision: probe it against the double response.
      std::string probeError;
      info.responseProbeError = ProbeResponseOperator(*sys, *sys->responseOperator, probeError);
      std::ostringstream note;
      note.precision(3);
      if (!(info.responseProbeError <= options.responseTolerance)) {
        note << backend->name() << " response operator deviates by " << info.responseProbeError
             << " from the double response (tolerance " << options.responseTolerance
             << (probeError.empty() ? "" : "; " + probeError)
             << "): edits are redone in double precision on the CPU";
        status.warnings.push_back(note.str());
        sys->responseOperator = MakeCpuBackend()->makeResponseOperator(sys->response, error);
        sys->responseRedoneInDouble = info.responseRedoneInDouble = true;
        sys->precisionNote = note.str();
      } else if (info.responseProbeError > 1e-13) {
        note << backend->name() << " response operator deviates by " << info.responseProbeError
             << " from the double response (within the tolerance " << options.responseTolerance << ")";
        sys->precisionNote = note.str();
      }
    }
    t[Stage::Condensation].ms += clock.lapMs();
  }
  t[Stage::Total].ms = total.elapsedMs();
  info.warnings = status.warnings;
  report(1.0, "done");
  out = sys;
  return status;
}

} // namespace

Status Precompute(const PrecomputeRequest& request, std::shared_ptr<const CondensedSystem>& system,
                  const std::atomic<bool>* cancel, const ProgressCallback& progress) {
  system.reset();
  try {
    return PrecomputeImpl(request, system, cancel, progress);
  } catch (const std::bad_alloc&) {
    return Status::Error("out of memory during the precompute");
  } catch (const std::exception& e) {
    return Status::Error(std::string("precompute failed: ") + e.what());
  }
}

namespace {

Status SolveImpl(const CondensedSystem& sys, const SolveInput& input, SolveResult& result) {
  StageClock total, clock;
  const NodeLayout& layout = sys.layout;
  result = SolveResult();
  result.method = sys.method;
  result.backend = sys.backendName;
  for (int s = 0; s < kNumStages; ++s) {
    result.timings.stages[s] = sys.info.precomputeTimings.stages[s];
    result.timings.stages[s].reused = true;
  }

  result.conditionEstimate = sys.info.conditionEstimate;
  result.elementOrder = sys.info.elementOrder;
  result.redoneInDouble = sys.responseRedoneInDouble;
  result.precisionNote = sys.precisionNote;
  Status status = Status::Ok();

  // Boundary condition: the ROI's prescribed displacements (and, for quadratic cells, the mean of
  // their ends at mid-edge ROI nodes).
  const Eigen::Index derived = static_cast<Eigen::Index>(sys.derivedMovable.size());
  const Eigen::Index movable = static_cast<Eigen::Index>(layout.roiPosition.size()) - derived;
  if (input.movableDisplacement.rows() != movable)
    return Status::Error("expected " + std::to_string(movable) + " ROI displacements, got " +
                         std::to_string(input.movableDisplacement.rows()));
  if (!input.movableDisplacement.allFinite())
    return Status::Error("prescribed displacements contain NaN or infinite values");
  Eigen::VectorXd roi = Eigen::VectorXd::Zero(3 * layout.roi);
  for (Eigen::Index k = 0; k < movable; ++k)
    if (layout.roiPosition[k] >= 0)
      roi.segment<3>(3 * layout.roiPosition[k]) = input.movableDisplacement.row(k).transpose();
  for (Eigen::Index d = 0; d < derived; ++d) {
    const int pos = layout.roiPosition[movable + d];
    if (pos < 0) continue;
    Eigen::Vector3d value = Eigen::Vector3d::Zero();
    for (int end : sys.derivedMovable[d])
      if (end >= 0) value += 0.5 * input.movableDisplacement.row(end).transpose();
    roi.segment<3>(3 * pos) = value;
  }
  result.timings[Stage::BoundaryCondition] = {clock.lapMs(), false};

  // Loads on the free DOFs.
  const int freeDofs = 3 * layout.freeNodes();
  Eigen::VectorXd load = Eigen::VectorXd::Zero(freeDofs);
  if (input.nodalLoads.size() > 0) {
    if (input.nodalLoads.rows() != sys.numOutputNodes)
      return Status::Error("nodal loads must have one row per mesh point");
    if (!input.nodalLoads.allFinite()) return Status::Error("nodal loads contain NaN values");
    for (int pos = 0; pos < layout.freeNodes(); ++pos)
      if (layout.meshNode[pos] < sys.numOutputNodes) // mid-edge nodes of quadratic cells get none
        load.segment<3>(3 * pos) = input.nodalLoads.row(layout.meshNode[pos]).transpose();
  }
  if (!input.gravity.allFinite()) return Status::Error("gravity contains NaN values");
  if (input.gravity.squaredNorm() > 0.0)
    for (int pos = 0; pos < layout.freeNodes(); ++pos)
      load.segment<3>(3 * pos) += sys.nodeMass[pos] * input.gravity;
  const bool hasLoad = load.squaredNorm() > 0.0;
  result.timings[Stage::Load] = {clock.lapMs(), false};

  Eigen::VectorXd keptFree, freeValues;
  const bool fullSolve = sys.method != SolveMethod::DenseResponse || input.recoverInterior;
  if (freeDofs == 0) {
    freeValues.resize(0);
  } else if (!fullSolve) {
    std::string error;
    if (!sys.responseOperator->apply(roi, keptFree, error))
      return Status::Error("dense response update failed: " + error);
    result.relativeResidual = sys.responseResidual;
    result.residualFromPrecompute = true;
    if (hasLoad) {
      Eigen::VectorXd loadResponse;
      double residual = 0.0;
      Status s = CachedLoadResponse(sys, load, loadResponse, residual, result.refinementSteps);
      if (!s)
        return s;
      result.relativeResidual = std::max(result.relativeResidual, residual);
      keptFree += loadResponse.head(keptFree.size());
    }
  } else {
    Eigen::VectorXd rhs = load;
    Eigen::VectorXd roiLoad; // -K_FR roi: non-zero only on the ROI-coupled (trailing) DOFs
    if (roi.size() > 0) {
      roiLoad.noalias() = -(sys.kfr * roi);
      rhs += roiLoad;
    }
    // With the ROI-coupled DOFs ordered last, the ROI part needs only a backward substitution;
    // a load's part is solved in full and reused while the load does not change.
    Eigen::MatrixXd initial;
    if (roi.size() > 0 && sys.factor.trailingDofs() > 0) {
      const SparseMatrix roiRhs = roiLoad.sparseView();
      Status s = sys.factor.solveTrailing(roiRhs, initial);
      if (!s)
        return s;
      if (hasLoad) {
        Eigen::VectorXd loadResponse;
        double loadResidual = 0.0;
        int loadSteps = 0; // the refinement of the whole solution below is what this solve reports
        s = CachedLoadResponse(sys, load, loadResponse, loadResidual, loadSteps);
        if (!s)
          return s;
        initial.col(0) += loadResponse;
      }
    }
    Eigen::MatrixXd x;
    Status s = RefinedSolve(sys, rhs, x, false, sys.residualTolerance, sys.maxRefinementSteps,
                            result.relativeResidual, result.refinementSteps, nullptr,
                            initial.size() > 0 ? &initial : nullptr);
    if (!s) return s;
    freeValues = x.col(0);
    keptFree = freeValues.head(3 * layout.keptFree);
  }
  result.timings[Stage::Solve] = {clock.lapMs(), false};

  // Outputs in the caller's numbering.
  auto valueOf = [&](int node, const Eigen::VectorXd& freeSource) -> Eigen::RowVector3d {
    const int pos = layout.dofNode[node];
    if (pos < 0) return Eigen::RowVector3d::Zero();
    if (pos >= layout.freeNodes()) return roi.segment<3>(3 * (pos - layout.freeNodes())).transpose();
    if (3 * pos + 2 >= freeSource.size()) return Eigen::RowVector3d::Zero();
    return freeSource.segment<3>(3 * pos).transpose();
  };
  result.keptDisplacement.resize(static_cast<Eigen::Index>(sys.kept.size()), 3);
  for (size_t k = 0; k < sys.kept.size(); ++k) result.keptDisplacement.row(k) = valueOf(sys.kept[k], keptFree);
  if (input.recoverInterior) {
    result.allDisplacement.resize(sys.numOutputNodes, 3);
    for (Eigen::Index i = 0; i < sys.numOutputNodes; ++i)
      result.allDisplacement.row(i) = valueOf(static_cast<int>(i), freeValues);
  }
  if (!result.keptDisplacement.allFinite() || !result.allDisplacement.allFinite() ||
      !std::isfinite(result.relativeResidual))
    return Status::Error("the solve produced non-finite values (ill-conditioned system?)");
  if (result.relativeResidual > 1e3 * sys.residualTolerance) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "relative residual " << result.relativeResidual << " after " << result.refinementSteps
        << " refinement steps misses the tolerance " << sys.residualTolerance
        << " (condition estimate " << result.conditionEstimate << ")";
    status.warnings.push_back(msg.str());
  }

  // Large-strain and inversion check on the caller's linear cells: every cell when the interior
  // was recovered, else the cells whose corners are all kept or constrained.
  if (sys.strainWarningLimit > 0.0) {
    DeformationReport deformation;
    if (input.recoverInterior) {
      deformation = CheckDeformation(sys.cornerMesh, result.allDisplacement, status.warnings,
                                     sys.strainWarningLimit);
    } else if (!sys.checkableCells.empty()) {
      Displacements known = Displacements::Zero(sys.numOutputNodes, 3);
      for (Eigen::Index k = 0; k < movable; ++k) known.row(sys.movableNodes[k]) = input.movableDisplacement.row(k);
      for (size_t k = 0; k < sys.kept.size(); ++k) known.row(sys.kept[k]) = result.keptDisplacement.row(k);
      deformation = CheckDeformation(sys.cornerMesh, known, status.warnings, sys.strainWarningLimit,
                                     &sys.checkableCells);
    }
    result.largestStrain = deformation.largestStrain;
    result.invertedCells = static_cast<long long>(deformation.invertedCells.size());
  }
  result.warnings = status.warnings;
  result.timings[Stage::Total] = {total.elapsedMs(), false};
  return status;
}

} // namespace

Status Solve(const CondensedSystem& system, const SolveInput& input, SolveResult& result) {
  try {
    return SolveImpl(system, input, result);
  } catch (const std::bad_alloc&) {
    return Status::Error("out of memory during the solve");
  } catch (const std::exception& e) {
    return Status::Error(std::string("solve failed: ") + e.what());
  }
}

SystemInfo Describe(const CondensedSystem& system) { return system.info; }

} // namespace faceplan
