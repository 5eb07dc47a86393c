#include "CondensedFEM.h"

#include "BlasThreads.h"
#include "CondensedSystem.h"
#include "ElementStiffness.h"
#include "MeshValidation.h"
#include "NodeSetValidation.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
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

namespace {

NodeLayout MakeLayout(const TetMesh& mesh, const NodeSets& sets) {
  const Eigen::Index n = mesh.numPoints();
  std::vector<char> used(n, 0), constrained(n, 0), kept(n, 0);
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int k = 0; k < 4; ++k) used[mesh.tets(e, k)] = 1;
  for (int i : sets.constrained) constrained[i] = 1;
  for (int i : sets.kept) kept[i] = 1;

  NodeLayout layout;
  layout.dofNode.assign(n, -1);
  auto place = [&](int node) {
    layout.dofNode[node] = static_cast<int>(layout.meshNode.size());
    layout.meshNode.push_back(node);
  };
  for (Eigen::Index i = 0; i < n; ++i)
    if (used[i] && !constrained[i] && kept[i]) place(static_cast<int>(i));
  layout.keptFree = static_cast<int>(layout.meshNode.size());
  for (Eigen::Index i = 0; i < n; ++i)
    if (used[i] && !constrained[i] && !kept[i]) place(static_cast<int>(i));
  layout.interior = static_cast<int>(layout.meshNode.size()) - layout.keptFree;
  layout.roiPosition.assign(sets.movable.size(), -1);
  for (size_t k = 0; k < sets.movable.size(); ++k) {
    const int node = sets.movable[k];
    if (!used[node]) continue;
    if (layout.dofNode[node] < 0) place(node); // a repeated id keeps its first position
    layout.roiPosition[k] = layout.dofNode[node] - layout.freeNodes();
  }
  layout.roi = static_cast<int>(layout.meshNode.size()) - layout.freeNodes();
  return layout;
}

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

// Per-edit flop counts decide between a dense product and a sparse solve (both exact).
SolveMethod ChooseMethod(const PrecomputeOptions& options, double keptDofs, double roiDofs,
                         double factorNonzeros, std::string& reason) {
  const double denseBytes = 8.0 * keptDofs * roiDofs;
  const double denseFlops = 2.0 * keptDofs * roiDofs;
  const double factorFlops = 4.0 * factorNonzeros;
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
        << factorFlops / 1e6 << " MFLOP as a factor solve";
    reason = why.str();
    return SolveMethod::DenseResponse;
  }
  why << "a factor solve (" << factorFlops / 1e6 << " MFLOP) is cheaper than the dense product ("
      << denseFlops / 1e6 << " MFLOP)";
  reason = why.str();
  return SolveMethod::CachedFactor;
}

// Columns of the response, solved in blocks: one single-threaded solve per core at a time, each
// with its own CHOLMOD workspace, blocks sized so the transient memory stays near 1 GB.
Status BuildResponse(CondensedSystem& sys, const PrecomputeOptions& options,
                     const std::atomic<bool>* cancel, const ProgressCallback& progress) {
  const Eigen::Index keptDofs = 3 * sys.layout.keptFree, roiDofs = sys.kfr.cols();
  const Eigen::Index freeDofs = sys.kff.rows();
  sys.response.resize(keptDofs, roiDofs);
  const int threads = static_cast<int>(std::max(1u, std::min(std::thread::hardware_concurrency(), 16u)));
  const double bytesPerColumn = 8.0 * 5.0 * double(std::max<Eigen::Index>(freeDofs, 1));
  const Eigen::Index memoryBlock = static_cast<Eigen::Index>(1.0e9 / (bytesPerColumn * threads));
  const Eigen::Index largestBlock = std::clamp<Eigen::Index>(std::min<Eigen::Index>(memoryBlock, options.responseBlockColumns), 8,
                                                      std::max(8, options.responseBlockColumns));
  const Eigen::Index evenShare = (roiDofs + threads - 1) / threads; // keep every core busy
  const Eigen::Index block = std::max<Eigen::Index>(1, std::min(largestBlock, evenShare));
  const Eigen::Index blocks = (roiDofs + block - 1) / block;

  ScopedBlasThreads singleThreadedBlas(1);
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
      Status s = sys.factor.solveConcurrently(rhs, x);
      if (!s) {
        std::lock_guard<std::mutex> lock(resultMutex);
        failure = s;
        return;
      }
      const Eigen::MatrixXd residual = sys.kff.selfadjointView<Eigen::Upper>() * x - rhs;
      double blockWorst = 0.0;
      for (Eigen::Index c = 0; c < cols; ++c) {
        const double norm = rhs.col(c).norm();
        if (norm > 0.0) blockWorst = std::max(blockWorst, residual.col(c).norm() / norm);
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
  if (!status) return status;

  sys->numMeshNodes = mesh.numPoints();
  sys->kept = request.sets.kept;
  sys->layout = MakeLayout(mesh, request.sets);
  const NodeLayout& layout = sys->layout;
  t[Stage::Separation].ms = clock.lapMs();
  report(0.05, "separation");
  if (cancelled()) return Status::Error("cancelled");

  AssemblyPattern pattern =
      BuildAssemblyPattern(mesh, layout.dofNode, static_cast<int>(layout.meshNode.size()));
  const double patternMs = clock.lapMs();
  std::shared_ptr<ComputeBackend> backend = options.backend ? options.backend : MakeCpuBackend();
  ComputeBackend::AssemblyTimings at;
  std::string error;
  if (!backend->assembleStiffness(mesh, request.materials, pattern, at, error)) {
    status.warnings.push_back(backend->name() + " backend failed (" + error + "); used the CPU");
    backend = MakeCpuBackend();
    at = {};
    backend->assembleStiffness(mesh, request.materials, pattern, at, error);
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
  sys->nodeMass = FreeNodeMass(mesh, request.materials, layout);
  t[Stage::Separation].ms += clock.lapMs();

  SystemInfo& info = sys->info;
  info.backend = sys->backendName;
  info.freeDofs = freeDofs;
  info.keptDofs = 3LL * layout.keptFree;
  info.roiDofs = 3LL * layout.roi;
  info.interiorDofs = 3LL * layout.interior;

  if (freeDofs > 0) {
    status = sys->factor.analyze(sys->kff);
    if (!status) return status;
    t[Stage::Reordering].ms = clock.lapMs();
    info.factorNonzeros = sys->factor.factorNonzeros();
    report(0.25, "reordering");
    if (cancelled()) return Status::Error("cancelled");
    Status fs = sys->factor.factorize(sys->kff);
    if (!fs) return fs;
    t[Stage::Factorization].ms = clock.lapMs();
    report(0.6, "factorization");
  }
  sys->method = ChooseMethod(options, double(info.keptDofs), double(info.roiDofs),
                             info.factorNonzeros, info.choiceReason);
  if (freeDofs == 0) sys->method = SolveMethod::CachedFactor;
  info.method = sys->method;

  if (sys->method == SolveMethod::DenseResponse) {
    Status rs = BuildResponse(*sys, options, cancel, progress);
    if (!rs) return rs;
    info.responseBytes = 8.0 * double(sys->response.size());
    sys->responseOperator = backend->makeResponseOperator(sys->response, error);
    if (!sys->responseOperator) {
      status.warnings.push_back(backend->name() + " could not hold the response (" + error +
                                "); edits run on the CPU");
      sys->responseOperator = MakeCpuBackend()->makeResponseOperator(sys->response, error);
    }
    t[Stage::Condensation].ms = clock.lapMs();
  }
  t[Stage::Total].ms = total.elapsedMs();
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

  // Boundary condition: the ROI's prescribed displacements.
  const Eigen::Index movable = static_cast<Eigen::Index>(layout.roiPosition.size());
  if (input.movableDisplacement.rows() != movable)
    return Status::Error("expected " + std::to_string(movable) + " ROI displacements, got " +
                         std::to_string(input.movableDisplacement.rows()));
  if (!input.movableDisplacement.allFinite())
    return Status::Error("prescribed displacements contain NaN or infinite values");
  Eigen::VectorXd roi = Eigen::VectorXd::Zero(3 * layout.roi);
  for (Eigen::Index k = 0; k < movable; ++k)
    if (layout.roiPosition[k] >= 0)
      roi.segment<3>(3 * layout.roiPosition[k]) = input.movableDisplacement.row(k).transpose();
  result.timings[Stage::BoundaryCondition] = {clock.lapMs(), false};

  // Loads on the free DOFs.
  const int freeDofs = 3 * layout.freeNodes();
  Eigen::VectorXd load = Eigen::VectorXd::Zero(freeDofs);
  if (input.nodalLoads.size() > 0) {
    if (input.nodalLoads.rows() != sys.numMeshNodes)
      return Status::Error("nodal loads must have one row per mesh point");
    if (!input.nodalLoads.allFinite()) return Status::Error("nodal loads contain NaN values");
    for (int pos = 0; pos < layout.freeNodes(); ++pos)
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
    result.residualIsBound = true;
    if (hasLoad) {
      std::lock_guard<std::mutex> lock(sys.loadMutex);
      if (sys.lastLoad.size() != load.size() || sys.lastLoad != load) {
        Eigen::MatrixXd x;
        Status s = sys.factor.solve(load, x);
        if (!s) return s;
        const double residual =
            (sys.kff.selfadjointView<Eigen::Upper>() * x - load).norm() / load.norm();
        sys.lastLoad = load;
        sys.lastLoadResponse = x.col(0);
        result.relativeResidual = std::max(result.relativeResidual, residual);
      }
      keptFree += sys.lastLoadResponse.head(keptFree.size());
    }
  } else {
    Eigen::VectorXd rhs = load;
    if (roi.size() > 0) rhs.noalias() -= sys.kfr * roi;
    Eigen::MatrixXd x;
    Status s = sys.factor.solve(rhs, x);
    if (!s) return s;
    freeValues = x.col(0);
    const double rhsNorm = rhs.norm();
    result.relativeResidual =
        rhsNorm > 0.0 ? (sys.kff.selfadjointView<Eigen::Upper>() * freeValues - rhs).norm() / rhsNorm
                      : freeValues.norm();
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
    result.allDisplacement.resize(sys.numMeshNodes, 3);
    for (Eigen::Index i = 0; i < sys.numMeshNodes; ++i)
      result.allDisplacement.row(i) = valueOf(static_cast<int>(i), freeValues);
  }
  if (!result.keptDisplacement.allFinite() || !result.allDisplacement.allFinite() ||
      !std::isfinite(result.relativeResidual))
    return Status::Error("the solve produced non-finite values (ill-conditioned system?)");
  result.timings[Stage::Total] = {total.elapsedMs(), false};
  return Status::Ok();
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
