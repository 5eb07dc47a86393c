#include "SparseSolver/TrailingResponse.h"
#include "Common/WorkerThreads.h"

#include "Common/BlasThreads.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

namespace faceplan {

namespace {
constexpr int kProbes = 4;
}

Status BuildTrailingResponse(const CholmodFactor& factor, const SparseMatrix& kffUpper,
                             const SparseMatrix& kfr, Eigen::Index keptDofs,
                             Eigen::Index blockColumns, const std::atomic<bool>* cancel,
                             const std::function<void(double)>& progress,
                             TrailingResponseResult& out) {
  const Eigen::Index freeDofs = kfr.rows(), roiDofs = kfr.cols();
  if (factor.trailingDofs() == 0)
    return Status::Error("internal: the factor has no trailing block");
  out.response.resize(keptDofs, roiDofs);
  out.probes = kProbes;

  // Random +-1 probe weights, fixed seed so that a precompute is reproducible.
  Eigen::MatrixXd weights(roiDofs, kProbes);
  std::mt19937 rng(20081201);
  for (Eigen::Index k = 0; k < weights.size(); ++k)
    weights.data()[k] = (rng() & 1u) ? 1.0 : -1.0;

  const int threads = WorkerThreads(16);
  const Eigen::Index block = std::max<Eigen::Index>(
      1, std::min(blockColumns, (roiDofs + threads - 1) / threads)); // keep every core busy
  const Eigen::Index blocks = (roiDofs + block - 1) / block;

  ScopedBlasThreads singleThreadedBlas(1); // one single-threaded solve per core
  std::atomic<Eigen::Index> nextBlock{0}, doneBlocks{0};
  std::mutex resultMutex;
  Status failure = Status::Ok();
  // Solutions stay in elimination order: copy out the kept rows, and form the probe sums there.
  const std::vector<int>& position = factor.eliminationPosition();
  Eigen::MatrixXd permutedProbe =
      Eigen::MatrixXd::Zero(freeDofs, kProbes); // (X * weights), permuted
  auto worker = [&] {
    CholmodFactor::TrailingWorkspace workspace;
    Eigen::MatrixXd localProbe = Eigen::MatrixXd::Zero(freeDofs, kProbes);
    for (Eigen::Index b = nextBlock++; b < blocks; b = nextBlock++) {
      if (cancel && cancel->load())
        break;
      const Eigen::Index c0 = b * block, cols = std::min(block, roiDofs - c0);
      Status s = factor.solveTrailing(kfr.middleCols(c0, cols), workspace);
      if (!s) {
        std::lock_guard<std::mutex> lock(resultMutex);
        failure = s;
        break;
      }
      const Eigen::Map<const Eigen::MatrixXd> x = workspace.permutedSolution();
      for (Eigen::Index c = 0; c < cols; ++c) { // disjoint columns per block
        double* column = out.response.col(c0 + c).data();
        const double* solution = x.col(c).data();
        for (Eigen::Index r = 0; r < keptDofs; ++r)
          column[r] = -solution[position[r]];
      }
      localProbe.noalias() += x * weights.middleRows(c0, cols);
      const Eigen::Index done = ++doneBlocks;
      if (progress)
        progress(double(done) / double(blocks));
    }
    std::lock_guard<std::mutex> lock(resultMutex);
    permutedProbe += localProbe;
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<Eigen::Index>(threads, blocks); ++t)
    pool.emplace_back(worker);
  worker(); // the calling thread works too
  for (auto& th : pool)
    th.join();
  if (cancel && cancel->load())
    return Status::Error("cancelled");
  if (!failure)
    return failure;

  const Eigen::MatrixXd probeSum = factor.fromEliminationOrder(permutedProbe);
  const Eigen::MatrixXd loads = kfr * weights;
  const Eigen::MatrixXd residual = kffUpper.selfadjointView<Eigen::Upper>() * probeSum - loads;
  out.residualEstimate = 0.0;
  for (int j = 0; j < kProbes; ++j) {
    const double norm = loads.col(j).norm(), r = residual.col(j).norm();
    const double relative = norm > 0.0 ? r / norm : r;
    out.residualEstimate = std::isfinite(relative) ? std::max(out.residualEstimate, relative)
                                                   : std::numeric_limits<double>::infinity();
  }
  return Status::Ok();
}

} // namespace faceplan
