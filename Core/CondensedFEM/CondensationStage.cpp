// SPDX-License-Identifier: BSD-3-Clause
// The Condensation stage: the dense response of the kept DOFs to the ROI DOFs.
#include "Common/ParallelFor.h"
#include "Common/WorkerThreads.h"
#include "CondensedFEM/DeformationCheck.h"
#include "CondensedFEM/PrecomputeStages.h"
#include "CondensedFEM/ResponseProbe.h"

#include "Common/BlasThreads.h"
#include "CondensedFEM/RefinedSolve.h"
#include "SparseSolver/TrailingResponse.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

namespace faceplan {

namespace {

// Columns of the response, solved in blocks: one single-threaded solve per core at a time, each
// with its own CHOLMOD workspace, blocks sized so the transient memory stays near 1 GB.
// First the cheap path (pruned substitutions on row-major blocks, residual estimated by random
// probes; TrailingResponse.h); when its estimate misses the tolerance, full solves with a residual
// and iterative refinement per column.
// `coupling` holds the columns' right-hand sides (K_FR, or K_FR times the segment basis).
Status BuildResponse(CondensedSystem& sys, const SparseMatrix& coupling,
                     const PrecomputeOptions& options, const std::atomic<bool>* cancel,
                     const ProgressCallback& progress) {
  const Eigen::Index keptDofs = 3 * sys.layout.keptFree, roiDofs = coupling.cols();
  const Eigen::Index freeDofs = sys.kff.rows();
  const int threads = WorkerThreads(16);
  const double bytesPerColumn = 8.0 * 5.0 * double(std::max<Eigen::Index>(freeDofs, 1));
  const Eigen::Index memoryBlock = static_cast<Eigen::Index>(1.0e9 / (bytesPerColumn * threads));
  const Eigen::Index largestBlock =
      std::clamp<Eigen::Index>(std::min<Eigen::Index>(memoryBlock, options.responseBlockColumns), 8,
                               std::max(8, options.responseBlockColumns));
  TrailingResponseResult fast;
  Status fs = BuildTrailingResponse(
      sys.factor, sys.kff, coupling, keptDofs, largestBlock, cancel,
      [&progress](double f) {
        if (progress)
          progress(0.6 + 0.4 * f, "dense response");
      },
      fast);
  if (!fs)
    return fs;
  std::ostringstream how;
  how.precision(3);
  const char* substitutions = sys.factor.trailingDofs() > 0
                                  ? "substitutions from the ROI-coupled trailing block"
                                  : "substitutions over the ROI-coupled DOFs' reach";
  if (fast.residualEstimate <= sys.residualTolerance) {
    sys.response = std::move(fast.response);
    sys.responseResidual = fast.residualEstimate;
    how << substitutions;
    if (sys.factor.trailingDofs() == 0)
      how << " (" << 100.0 * fast.forwardFlopsFraction << " % of a whole forward substitution)";
    how << ", backward only to the kept rows (" << 100.0 * fast.backwardFlopsFraction
        << " % of a whole backward substitution); relative residual " << fast.residualEstimate
        << " estimated with " << fast.probes << " random probes";
    sys.info.responsePath = how.str();
    return Status::Ok();
  }
  how << "full solves with per-column residuals and refinement (the probe estimate "
      << fast.residualEstimate << " of the " << substitutions << " missed " << sys.residualTolerance
      << ")";
  sys.info.responsePath = how.str();
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
      if (cancel && cancel->load())
        return;
      const Eigen::Index c0 = b * block, cols = std::min(block, roiDofs - c0);
      const Eigen::MatrixXd rhs = Eigen::MatrixXd(coupling.middleCols(c0, cols));
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
      if (progress)
        progress(0.6 + 0.4 * double(doneBlocks.load()) / double(blocks), "dense response");
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<Eigen::Index>(threads, blocks); ++t)
    pool.emplace_back(worker);
  worker(); // the calling thread works too
  for (auto& th : pool)
    th.join();
  if (progress)
    progress(1.0, "dense response");
  if (cancel && cancel->load())
    return Status::Error("cancelled");
  if (!failure)
    return failure;
  sys.responseResidual = worst;
  return Status::Ok();
}

} // namespace

Status Condense(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  const bool segments = sys.method == SolveMethod::RigidSegments;
  if (sys.method != SolveMethod::DenseResponse && !segments)
    return Status::Ok();
  const PrecomputeOptions& options = state.request.options;
  SystemInfo& info = sys.info;
  ComputeBackend& backend = *state.backend;
  if (!state.backendResponse) {
    Status rs = BuildResponse(sys, segments ? state.segmentCoupling : sys.kfr, options,
                              state.cancel, state.progress);
    if (!rs)
      return rs;
  }
  info.responseBytes = 8.0 * double(sys.response.size());
  Status held;
  if (state.backendOperator)
    sys.responseOperator = std::move(state.backendOperator);
  else
    held = backend.makeResponseOperator(sys.response, sys.responseOperator);
  if (!held || !sys.responseOperator) {
    state.status.warnings.push_back(backend.name() + " could not hold the response (" +
                                    held.message + "); edits run on the CPU");
    const Status onCpu = MakeCpuBackend()->makeResponseOperator(sys.response, sys.responseOperator);
    if (!onCpu)
      return onCpu;
  } else if (options.backend) {
    // A backend may hold the response in lower precision: probe it against the double response.
    std::string probeError;
    StageClock probeClock;
    info.responseProbeError =
        ProbeResponseOperator(sys.response, *sys.responseOperator, kProbeFullBytes,
                              info.responseProbeRowFraction, probeError);
    info.responseProbeMs = probeClock.elapsedMs();
    std::ostringstream note;
    note.precision(3);
    if (!(info.responseProbeError <= options.responseTolerance)) {
      note << backend.name() << " response operator deviates by " << info.responseProbeError
           << " from the double response (tolerance " << options.responseTolerance
           << (probeError.empty() ? "" : "; " + probeError)
           << "): edits are redone in double precision on the CPU";
      state.status.warnings.push_back(note.str());
      const Status onCpu =
          MakeCpuBackend()->makeResponseOperator(sys.response, sys.responseOperator);
      if (!onCpu)
        return onCpu;
      sys.responseRedoneInDouble = info.responseRedoneInDouble = true;
      sys.precisionNote = note.str();
    } else if (info.responseProbeError > 1e-13) {
      note << backend.name() << " response operator deviates by " << info.responseProbeError
           << " from the double response (within the tolerance " << options.responseTolerance
           << ")";
      sys.precisionNote = note.str();
    }
  }
  state.segmentCoupling = SparseMatrix();
  BuildStrainBounds(sys);
  state.time(Stage::Condensation).ms += state.clock.lapMs();
  return Status::Ok();
}

} // namespace faceplan
