// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/TrailingResponse.h"
#include "Common/WorkerThreads.h"

#include "Common/BlasThreads.h"
#include "Common/UninitializedVector.h"
#include "SparseSolver/Blas.h"
#include "SparseSolver/PrunedBackSubstitution.h"
#include "SparseSolver/PrunedForwardSubstitution.h"

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

// The forward substitution y = L^-1 b into the row-major block x (n x `columns`) for the
// right-hand sides b = `rhs` columns [c0, c0 + columns): with a trailing block (t > 0) b must be
// zero above it and the substitution is a dense triangular solve there; otherwise it runs over
// the reach of b's rows. Afterwards the rows the backward substitution reads as data hold y.
struct ForwardSubstitution {
  const std::vector<int>& position;
  int first = 0; // first row of the trailing block (n when there is none)
  const Eigen::MatrixXd& trailingBlock;
  const PrunedForwardSubstitution* reach = nullptr; // without a trailing block

  Status operator()(const SparseMatrix& rhs, Eigen::Index c0, int columns, double* x,
                    std::vector<double>& scratch) const {
    const int t = static_cast<int>(trailingBlock.rows());
    if (reach)
      reach->clearReach(x, columns);
    else
      std::fill(x + size_t(first) * columns, x + size_t(first + t) * columns, 0.0);
    for (int c = 0; c < columns; ++c)
      for (SparseMatrix::InnerIterator it(rhs, c0 + c); it; ++it) {
        const int p = position[it.row()];
        if (!reach && p < first)
          return Status::Error("internal: right-hand side outside the trailing DOFs");
        x[size_t(p) * columns + c] = it.value();
      }
    if (reach) {
      reach->solve(x, columns, scratch);
      return Status::Ok();
    }
    // Row-major Y_t is the column-major Y_t^T: Y_t^T := B_t^T L_tt^-T, i.e. Y_t := L_tt^-1 B_t.
    const double one = 1.0;
    dtrsm_("R", "L", "T", "N", &columns, &t, &one, trailingBlock.data(), &t,
           x + size_t(first) * columns, &columns);
    return Status::Ok();
  }
};

} // namespace

Status BuildTrailingResponse(const CholmodFactor& factor, const SparseMatrix& kffUpper,
                             const SparseMatrix& kfr, Eigen::Index keptDofs,
                             Eigen::Index blockColumns, const std::atomic<bool>* cancel,
                             const std::function<void(double)>& progress,
                             TrailingResponseResult& out) {
  const Eigen::Index freeDofs = kfr.rows(), roiDofs = kfr.cols();
  const cholmod_factor_struct* numeric = factor.numericFactor();
  const int t = factor.trailingDofs();
  if (!numeric || factor.trailingFactorBlock().rows() != t)
    return Status::Error("internal: the response needs a numeric factor");
  const int n = static_cast<int>(freeDofs);
  const std::vector<int>& position = factor.eliminationPosition();

  // Without a trailing block the forward substitution runs over the reach of the coupled rows.
  PrunedForwardSubstitution reach;
  if (t == 0) {
    std::vector<int> coupledPositions;
    for (Eigen::Index c = 0; c < kfr.outerSize(); ++c)
      for (SparseMatrix::InnerIterator it(kfr, c); it; ++it)
        coupledPositions.push_back(position[it.row()]);
    if (Status s = reach.prepare(*numeric, coupledPositions); !s)
      return s;
  }
  const ForwardSubstitution forward{position, n - t, factor.trailingFactorBlock(),
                                    t == 0 ? &reach : nullptr};
  const std::vector<char>* reached = t == 0 ? &reach.reached() : nullptr;
  const int firstNonZero = t > 0 ? n - t : 0; // below it the backward substitution reads data

  // The response needs the kept rows only; the probe check below needs every row.
  PrunedBackSubstitution keptRows, allRows;
  const std::vector<int> keptPositions(position.begin(), position.begin() + keptDofs);
  if (Status s = keptRows.prepare(*numeric, keptPositions); !s)
    return s;
  if (Status s = allRows.prepare(*numeric, {}); !s)
    return s;
  out.backwardFlopsFraction = keptRows.flopsPerColumn() / std::max(1.0, allRows.flopsPerColumn());
  out.forwardFlopsFraction =
      t == 0 ? reach.flopsPerColumn() / std::max(1.0, allRows.flopsPerColumn()) : 0.0;
  out.response.resize(keptDofs, roiDofs);
  out.probes = kProbes;

  const int threads = WorkerThreads(16);
  const Eigen::Index block = std::max<Eigen::Index>(
      1, std::min(blockColumns, (roiDofs + threads - 1) / threads)); // keep every core busy
  const Eigen::Index blocks = (roiDofs + block - 1) / block;

  // The probe's right-hand sides (see below), solved on every row as one more task of the pool.
  Eigen::MatrixXd weights(roiDofs, kProbes);
  std::mt19937 rng(20081201); // fixed seed: a precompute is reproducible
  for (Eigen::Index k = 0; k < weights.size(); ++k)
    weights.data()[k] = (rng() & 1u) ? 1.0 : -1.0;
  const Eigen::MatrixXd loads = kfr * weights;
  const SparseMatrix sparseLoads = loads.sparseView();
  std::vector<double> probe(size_t(n) * kProbes);

  ScopedBlasThreads singleThreadedBlas(1); // one single-threaded solve per core
  std::atomic<Eigen::Index> nextTask{0}, doneBlocks{0};
  std::mutex resultMutex;
  Status failure = Status::Ok();
  auto fail = [&](const Status& s) {
    std::lock_guard<std::mutex> lock(resultMutex);
    failure = s;
  };
  constexpr Eigen::Index kRowTile = 32; // rows copied out per tile: column writes stay contiguous
  auto worker = [&] {
    // x need not start as zero: the forward substitution sets the rows the backward one reads
    // as data and the backward one clears or overwrites the others (x is reused block to block).
    // Left uninitialized, its pages are first touched by the substitutions themselves.
    UninitializedVector<double> x;
    std::vector<double> scratch;
    for (Eigen::Index task = nextTask++; task <= blocks; task = nextTask++) {
      if (cancel && cancel->load())
        break;
      if (task == blocks) { // the probe
        if (Status s = forward(sparseLoads, 0, kProbes, probe.data(), scratch); !s) {
          fail(s);
          break;
        }
        allRows.solve(probe.data(), kProbes, firstNonZero, scratch, reached);
        continue;
      }
      x.resize(size_t(n) * block);
      const Eigen::Index c0 = task * block;
      const int cols = static_cast<int>(std::min(block, roiDofs - c0));
      if (Status s = forward(kfr, c0, cols, x.data(), scratch); !s) {
        fail(s);
        break;
      }
      keptRows.solve(x.data(), cols, firstNonZero, scratch, reached);
      for (Eigen::Index r0 = 0; r0 < keptDofs; r0 += kRowTile) { // disjoint columns per block
        const Eigen::Index r1 = std::min(keptDofs, r0 + kRowTile);
        for (int c = 0; c < cols; ++c) {
          double* column = out.response.col(c0 + c).data();
          for (Eigen::Index r = r0; r < r1; ++r)
            column[r] = -x[size_t(position[r]) * cols + c];
        }
      }
      const Eigen::Index done = ++doneBlocks;
      if (progress)
        progress(double(done) / double(blocks));
    }
  };
  std::vector<std::thread> pool;
  for (int th = 1; th < std::min<Eigen::Index>(threads, blocks + 1); ++th)
    pool.emplace_back(worker);
  worker(); // the calling thread works too
  for (auto& th : pool)
    th.join();
  if (cancel && cancel->load())
    return Status::Error("cancelled");
  if (!failure)
    return failure;

  // Accuracy check without a residual per column: for a few random +-1 weight vectors w, K_FF z =
  // K_FR w was solved on every row with the same substitutions; put the response's own prediction
  // -response * w in z's kept rows and take the relative residual of that vector. It estimates
  // the residual an edit sees (the root mean square of the column residuals in expectation), and
  // a kept row the pruned solve got wrong shows in it.
  const Eigen::MatrixXd keptPrediction = out.response * weights;
  Eigen::MatrixXd combined(n, kProbes);
  for (Eigen::Index dof = 0; dof < n; ++dof)
    for (int j = 0; j < kProbes; ++j)
      combined(dof, j) =
          dof < keptDofs ? -keptPrediction(dof, j) : probe[size_t(position[dof]) * kProbes + j];
  const Eigen::MatrixXd residual = kffUpper.selfadjointView<Eigen::Upper>() * combined - loads;
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
