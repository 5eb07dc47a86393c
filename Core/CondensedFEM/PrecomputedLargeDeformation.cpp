// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/PrecomputedLargeDeformation.h"

#include "Backend/ComputeBackend.h"
#include "Common/BlasThreads.h"
#include "Common/ExceptionBoundary.h"
#include "Common/HelperThreads.h"
#include "Common/ParallelFor.h"
#include "Common/UninitializedVector.h"
#include "Common/WorkerThreads.h"
#include "CondensedFEM/LargeDeformationProblem.h"
#include "CondensedFEM/LbfgsHistory.h"
#include "Mesh/InputValidation.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "SparseSolver/MultifrontalWorkspace.h"
#include "SparseSolver/SinglePrecisionFactor.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <thread>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace faceplan {

using namespace large_deformation;

namespace {

// The background refactorization runs at the lowest priority (and the threads it starts inherit
// it): during a drag the next edit's solve, which the user waits for, then has the cores, and the
// refactorization fills the time between edits.
void YieldToInteractiveWork() {
#ifdef __linux__
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
#endif
}

// The tangents of factors that are gone, kept for the next factor's copy: a fresh copy's
// megabytes cost the page faults of their mapping (several milliseconds on the face's tangent),
// while a kept matrix of the same pattern is overwritten in place. Holds at most two.
class TangentBin {
public:
  void take(SparseMatrix& into) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!kept_.empty()) {
      into.swap(kept_.back());
      kept_.pop_back();
    }
  }
  void give(SparseMatrix& from) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (kept_.size() < 2) {
      kept_.emplace_back();
      kept_.back().swap(from);
    }
  }

private:
  std::mutex mutex_;
  std::vector<SparseMatrix> kept_;
};

// A numeric factor of the tangent at state u with the DOFs `prescribed` pinned (their rows and
// columns zero, their diagonal kept), and the unpinned tangent for the predictor's products.
struct TangentFactor {
  TangentFactor() = default;
  TangentFactor(const TangentFactor&) = delete;
  TangentFactor& operator=(const TangentFactor&) = delete;
  ~TangentFactor() {
    if (const std::shared_ptr<TangentBin> to = bin.lock())
      to->give(tangent);
  }
  CholmodFactor factor;         // empty when `single` was factored directly
  SinglePrecisionFactor single; // empty unless options.singlePrecisionFactor
  SparseMatrix tangent;
  std::weak_ptr<TangentBin> bin; // where `tangent` goes when this factor is gone
  // The backend's copy of `single` and `tangent` (null: the CPU's), and why there is none when a
  // backend was asked.
  std::shared_ptr<FactorOnDevice> device;
  std::string deviceError;
  // The state it was made at, its contact and its internal force: a predictor may start there.
  Eigen::VectorXd state, force;
  std::vector<char> prescribed;
};

// x = F^-1 b on the CPU with the factor in the precision it was made in (singlePrecision: the
// options'); pinned DOFs are the caller's. Safe beside other threads' solves with the same factor
// (the worker's corrections read a factor the solves already use).
Status SolveOnCpu(const TangentFactor& f, bool singlePrecision, const Eigen::VectorXd& b,
                  Eigen::VectorXd& x) {
  if (singlePrecision)
    return f.single.solve(b, x); // with one BLAS thread, as below
  Eigen::MatrixXd column;
  // One right-hand side: its supernodes' triangular solves are too small for threaded BLAS, whose
  // thread hand-offs cost more than they save (most of all on a loaded machine).
  ScopedBlasThreads serial(1, BlasScope::Pinned);
  const Status solved = f.factor.solveConcurrently(b, column);
  if (solved)
    x = column.col(0);
  return solved;
}

// A set of DOFs and where their columns lie in every tangent's values (all tangents share one
// pattern): per DOF k of the set, entries[start[k] ...] as (value index, the other DOF), each
// off-diagonal entry once for its column and once for its row. Found in one pass over the upper
// triangle, so that the columns are read without touching the rest:
// - the movable nodes' DOFs, the only ones a target moves: the tangent's product with a move on
//   them, for the yardstick |K_0 u_prescribed| of each solve and the predictor's K move;
// - the lift-off DOFs released since a factor was made: their columns, for the Schur coupling.
struct DofColumns {
  std::vector<int> dofs;
  std::vector<char> has; // per DOF: in the set
  std::vector<int> start;
  std::vector<std::pair<int, int>> entries;
  // The rows that the set's columns reach (a few thousand, where a product has every DOF's), and
  // per entry its row's place among them.
  std::vector<int> rowOf;
  std::vector<int> rowPlace;

  DofColumns() = default;
  DofColumns(const SparseMatrix& upper, std::vector<int> set) : dofs(std::move(set)) {
    has.assign(static_cast<size_t>(upper.cols()), 0);
    std::vector<int> column(static_cast<size_t>(upper.cols()), -1);
    for (size_t k = 0; k < dofs.size(); ++k) {
      column[dofs[k]] = static_cast<int>(k);
      has[dofs[k]] = 1;
    }
    std::vector<std::vector<std::pair<int, int>>> of(dofs.size());
    const int* outer = upper.outerIndexPtr();
    const int* inner = upper.innerIndexPtr();
    for (Eigen::Index j = 0; j < upper.outerSize(); ++j)
      for (int q = outer[j]; q < outer[j + 1]; ++q) {
        const int i = inner[q];
        if (column[j] >= 0)
          of[column[j]].emplace_back(q, i);
        if (i != j && column[i] >= 0)
          of[column[i]].emplace_back(q, static_cast<int>(j));
      }
    start.assign(1, 0);
    for (const auto& list : of) {
      entries.insert(entries.end(), list.begin(), list.end());
      start.push_back(static_cast<int>(entries.size()));
    }
    std::vector<int> place(static_cast<size_t>(upper.cols()), -1);
    rowPlace.reserve(entries.size());
    for (const auto& [q, row] : entries) {
      if (place[row] < 0) {
        place[row] = static_cast<int>(rowOf.size());
        rowOf.push_back(row);
      }
      rowPlace.push_back(place[row]);
    }
  }

  // K v on the rows the set's columns reach (rowOf), for the symmetric matrix whose upper triangle
  // holds `values` in the shared pattern; only v's entries on the set's DOFs are read (the
  // caller's v is zero elsewhere).
  Eigen::VectorXd reachedProduct(const double* values, const Eigen::VectorXd& v) const {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rowOf.size()));
    for (size_t k = 0; k < dofs.size(); ++k) {
      const double m = v[dofs[k]];
      if (m == 0.0)
        continue;
      for (int e = start[k]; e < start[k + 1]; ++e)
        out[rowPlace[e]] += values[entries[e].first] * m;
    }
    return out;
  }

  // |K v|, for the same K and v.
  double productNorm(const double* values, const Eigen::VectorXd& v) const {
    return reachedProduct(values, v).norm();
  }

  // out = K v on every row, for the same K and v.
  void multiply(const double* values, const Eigen::VectorXd& v, Eigen::VectorXd& out) const {
    const Eigen::VectorXd reached = reachedProduct(values, v);
    out.setZero(v.size());
    for (size_t p = 0; p < rowOf.size(); ++p)
      out[rowOf[p]] = reached[static_cast<Eigen::Index>(p)];
  }

  // The set's columns of the same matrix (n x dofs.size()).
  Eigen::MatrixXd columns(const double* values, Eigen::Index n) const {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(dofs.size()));
    for (size_t k = 0; k < dofs.size(); ++k)
      for (int e = start[k]; e < start[k + 1]; ++e)
        out(entries[e].second, static_cast<Eigen::Index>(k)) += values[entries[e].first];
    return out;
  }
};

// out[0, rows) = sum over j < k of v[j] column[j][first, first + rows): four columns a pass, so
// that the sum is read and written a quarter as often. Eight-wide AVX2 where the CPU has it (the
// build's baseline is SSE2's four), chosen at load time; without FMA contraction, so that both
// versions give the same bits.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void SumOfColumns(const float* const* column, const float* v, int k, int first, int rows,
                  float* out) {
  std::fill_n(out, rows, 0.0f);
  int j = 0;
  for (; j + 4 <= k; j += 4) {
    const float *c0 = column[j] + first, *c1 = column[j + 1] + first, *c2 = column[j + 2] + first,
                *c3 = column[j + 3] + first;
    const float v0 = v[j], v1 = v[j + 1], v2 = v[j + 2], v3 = v[j + 3];
    for (int i = 0; i < rows; ++i)
      out[i] += v0 * c0[i] + v1 * c1[i] + v2 * c2[i] + v3 * c3[i];
  }
  for (; j < k; ++j) {
    const float* c = column[j] + first;
    for (int i = 0; i < rows; ++i)
      out[i] += v[j] * c[i];
  }
}

// The Schur coupling (see QuasiNewton::prepareReleased) of every lift-off DOF pinned in the rest
// factor, made once on the worker thread after the precompute, so that a solve from rest couples
// whichever of them it releases exactly without substituting their columns.
struct RestReleases {
  std::vector<int> column;   // per DOF: its column in w, schur and tangentColumns, or -1
  Eigen::MatrixXf w;         // n x |L|: G A_L
  Eigen::MatrixXd schur;     // A_LL - A_L^T W
  DofColumns tangentColumns; // A_L: where the rest tangent holds their columns
};

// The released DOFs' Schur coupling in the form an iteration reads: W's columns in single
// precision (read once per iteration, like the single-precision factor, and need be no more
// accurate), read where they lie (the rest factor's RestReleases, or a few columns substituted for
// another factor), A_R's entries, and S's Cholesky factor. W^T b is A_R^T G b (G is symmetric),
// the few entries of A_R against the substitution's result, so W is read once, not twice.
struct ReleaseCoupling {
  std::vector<int> dofs;          // empty: no coupling
  std::vector<const float*> w;    // each DOF's column of W (n floats)
  UninitializedVector<float> own; // the columns substituted for another factor
  // A_R: DOF j's column is column setColumn[j] of `set` in the tangent's `values`. For the rest
  // factor `set` is its RestReleases' tangentColumns, and holds those RestReleases (whose columns
  // `w` points into) alive.
  std::shared_ptr<const DofColumns> set;
  std::vector<int> setColumn;
  const double* values = nullptr;
  Eigen::LLT<Eigen::MatrixXd> schur;
  Eigen::Index n = 0;

  int columns() const { return static_cast<int>(dofs.size()); }
  void clear() {
    dofs.clear();
    w.clear();
    set.reset();
    setColumn.clear();
    values = nullptr;
    n = 0;
  }

  // A_R^T x.
  Eigen::VectorXd tangentProduct(const Eigen::VectorXd& x) const {
    Eigen::VectorXd t(columns());
    for (int j = 0; j < columns(); ++j) {
      const int c = setColumn[static_cast<size_t>(j)];
      double sum = 0.0;
      for (int e = set->start[c]; e < set->start[c + 1]; ++e)
        sum += values[set->entries[e].first] * x[set->entries[e].second];
      t[j] = sum;
    }
    return t;
  }
  // x -= W v.
  void subtractProduct(const Eigen::VectorXd& v, Eigen::VectorXd& x) const {
    const Eigen::VectorXf vf = v.cast<float>();
    Eigen::VectorXf product(n);
    byRows([&](int first, int rows) {
      SumOfColumns(w.data(), vf.data(), columns(), first, rows, product.data() + first);
    });
    x -= product.cast<double>();
  }

private:
  // W is read from memory each time (tens of megabytes with many DOFs released): its rows in two
  // halves, one per core.
  static constexpr int kParts = 2;
  template <class Work> void byRows(const Work& work) const {
    RunOnHelpers(kParts, [&](int part) {
      const int first = static_cast<int>(std::int64_t(n) * part / kParts);
      const int last = static_cast<int>(std::int64_t(n) * (part + 1) / kParts);
      if (last > first)
        work(first, last - first);
    });
  }
};

// The tangent as the factor sees it. The couplings of the nodes pinned in every solve (constrained
// nodes with no lift-off DOF) are zero in every pinned tangent, so they are left out of the pattern
// that is ordered and analysed: in the whole mesh's pattern the ordering makes fill for them. On
// the face's scenes a twentieth of the nodes are such, and leaving them out saves a fifth to a
// quarter of the factorization's flops and an eighth to a sixth of the factor's non-zeros, which
// every substitution reads. Those nodes' DOFs keep their diagonal, as every pinned DOF does.
struct FactorPattern {
  SparseMatrix upper;      // the pattern (values unused)
  std::vector<int> source; // per entry, its index in the whole mesh's tangent
  CholmodFactor analysis;  // its ordering and symbolic analysis, made once
  // The rest tangent's single-precision factorization, which later ones reuse in part
  // (PrecomputedLargeDeformationOptions::reuseTolerance); made once, then only read.
  MultifrontalReference rest;
  double reuseTolerance = -1.0; // < 0: no reuse
  // The rest tangent's cells (packed), which cells near rest keep in later factorizations.
  std::vector<double> restPacked;
  // The rest factor, whose tangent is the rest tangent assembled (the whole mesh's pattern), and
  // per packed cell entry its entry there: a later factorization starts from the rest tangent and
  // adds what the cells that left rest changed, instead of summing every cell's entries again (a
  // gather over tens of megabytes).
  std::shared_ptr<const TangentFactor> restFactor;
  std::vector<int> packedEntry;
};

// What a factorization assembles into, kept from one to the next by each thread that factors: the
// cells' packed tangents are tens of megabytes, which fresh each time cost their zero-fill and page
// faults.
struct TangentBuffers {
  AssemblyPattern pattern;
  std::vector<double> packed;
  SparseMatrix factored;      // the pinned tangent on FactorPattern's entries
  std::vector<char> restHeld; // per cell: `packed` holds its rest tangent (NearRestTangents)
  // The entries of `factored` that the contact pinnedFor pins: off the diagonal, and on it.
  std::vector<char> pinnedFor;
  std::vector<int> pinnedEntries, pinnedDiagonal;
  // Kept from one factorization on this thread to the next (the tangents share one pattern), and
  // the factors' values, kept when a factor is gone for the next (shared by the solve's and the
  // worker's buffers).
  MultifrontalWorkspace workspace;
  std::shared_ptr<FactorValueBin> values;
  std::shared_ptr<TangentBin> tangents; // likewise shared
};

// The factor state's tangent columns of set.dofs with the rows pinned in `prescribed` and the set's
// own zeroed (columns), and their rows of the set (block).
void ReleasedColumns(const TangentFactor& factor, const std::vector<char>& prescribed,
                     const DofColumns& set, Eigen::MatrixXd& columns, Eigen::MatrixXd& block) {
  const std::vector<int>& dofs = set.dofs;
  const Eigen::Index n = factor.tangent.cols(), k = static_cast<Eigen::Index>(dofs.size());
  columns = set.columns(factor.tangent.valuePtr(), n);
  block.resize(k, k);
  for (Eigen::Index j = 0; j < k; ++j)
    for (Eigen::Index i = 0; i < k; ++i)
      block(i, j) = columns(dofs[i], j);
  for (Eigen::Index j = 0; j < k; ++j) {
    ZeroPrescribed(prescribed, columns.col(j));
    for (int d : dofs)
      columns(d, j) = 0.0;
  }
}

// The coupling of every lift-off DOF pinned in `factor` (RestReleases), from one substitution of
// all their columns at once. Null where it fails or would be too large (more than `most` DOFs, or
// its two n x |L| matrices of doubles above 512 MB): a solve then couples a few DOFs at a time, as
// with any other factor.
std::shared_ptr<const RestReleases> MakeRestReleases(const TangentFactor& factor,
                                                     const std::vector<int>& liftOff, int most) {
  constexpr double kMostBytes = 512e6;
  std::vector<int> dofs;
  for (int d : liftOff)
    if (factor.prescribed[d])
      dofs.push_back(d);
  const double bytes = 2.0 * 8.0 * double(dofs.size()) * double(factor.tangent.cols());
  if (dofs.empty() || dofs.size() > static_cast<size_t>(most) || bytes > kMostBytes ||
      factor.single.rows() != factor.tangent.cols())
    return nullptr;
  DofColumns set(factor.tangent, dofs);
  Eigen::MatrixXd columns, block, w;
  ReleasedColumns(factor, factor.prescribed, set, columns, block);
  if (!factor.single.solve(columns, w))
    return nullptr;
  for (Eigen::Index j = 0; j < w.cols(); ++j)
    ZeroPrescribed(factor.prescribed, w.col(j));
  auto made = std::make_shared<RestReleases>();
  made->column.assign(static_cast<size_t>(factor.tangent.cols()), -1);
  for (size_t j = 0; j < dofs.size(); ++j)
    made->column[dofs[j]] = static_cast<int>(j);
  made->schur = block - columns.transpose() * w;
  made->w = w.cast<float>();
  made->tangentColumns = std::move(set);
  return made;
}

// Assembles the tangent at u into `buffers` and factors it with the DOFs `prescribed` pinned, or,
// given `contactAtU` (targets and loads at u), with the contact that Newton's rule gives at u from
// `prescribed` and the force evaluated here. False (with a message) when a cell is inverted or the
// pinned tangent is not positive definite. `keepRest`: the factorization is kept as fp.rest (the
// precompute's, which alone may write fp); the others reuse fp.rest.
Status FactorTangent(const Structure& st, const FactorPattern& fp, TangentBuffers& buffers,
                     const Eigen::VectorXd& u, const std::vector<char>& prescribed,
                     Problem* contactAtU, bool singlePrecision, ComputeBackend* backend,
                     std::shared_ptr<TangentFactor>& out, StageTimings* timings,
                     MultifrontalReference* keepRest = nullptr) {
  StageClock clock;
  Evaluation ev;
  std::vector<double>& packed = buffers.packed;
  AssemblyPattern& pattern = buffers.pattern;
  // Where the factorization reuses the rest factor, cells that are nearly at rest keep their rest
  // tangent: a cell's tangent changes with its deformation gradient by about its modulus times
  // |F - I|, so within a quarter of the reuse tolerance its entries change by less than the
  // tolerance of their diagonal (on the main demo's cut three quarters of the cells).
  NearRestTangents nearRest;
  const bool reusing = !keepRest && fp.reuseTolerance >= 0.0 && fp.rest.made();
  if (reusing) {
    nearRest.rest = &fp.restPacked;
    nearRest.held = &buffers.restHeld;
    nearRest.limit = 0.25 * fp.reuseTolerance;
  }
  if (!Evaluate(st, u, ev, &packed, nullptr, reusing ? &nearRest : nullptr))
    return Status::Error("a cell is inverted at the state to factor");
  if (timings)
    (*timings)[Stage::ElementStiffness].ms += clock.lapMs();
  // Only where few cells left rest: each changed cell's entries are added in place, at about
  // twice the cost per cell of the whole sum's gather.
  if (reusing && !fp.packedEntry.empty() &&
      3 * std::count(buffers.restHeld.begin(), buffers.restHeld.end(), 0) <=
          static_cast<std::ptrdiff_t>(buffers.restHeld.size()))
    AssembleChangedCells(fp.restFactor->tangent.valuePtr(), fp.restPacked, packed.data(),
                         buffers.restHeld, fp.packedEntry, pattern);
  else
    AssembleFromPacked(packed.data(), pattern);
  auto made = std::make_shared<TangentFactor>();
  if (buffers.tangents) {
    buffers.tangents->take(made->tangent);
    made->bin = buffers.tangents;
  }
  // The bin's matrices all have this system's pattern: one it gave takes the assembled values by
  // a swap (the next assembly writes into its storage), a fresh one by a copy.
  if (made->tangent.nonZeros() == pattern.upper.nonZeros() &&
      made->tangent.cols() == pattern.upper.cols())
    made->tangent.swap(pattern.upper);
  else
    made->tangent = pattern.upper;
  made->state = u;
  made->prescribed = prescribed;
  if (contactAtU) {
    contactAtU->prescribed = prescribed;
    UpdateContact(*contactAtU, u, 1.0, &ev.force);
    made->prescribed = contactAtU->prescribed;
  }
  made->force = std::move(ev.force);
  SparseMatrix& factored = buffers.factored;
  if (factored.nonZeros() != fp.upper.nonZeros())
    factored = fp.upper;
  const double* tangent = made->tangent.valuePtr();
  double* values = factored.valuePtr();
  for (size_t k = 0; k < fp.source.size(); ++k)
    values[k] = tangent[fp.source[k]];
  if (buffers.pinnedFor != made->prescribed) { // a new contact
    FindPinnedEntries(factored, made->prescribed, buffers.pinnedEntries, buffers.pinnedDiagonal);
    buffers.pinnedFor = made->prescribed;
  }
  for (int k : buffers.pinnedEntries)
    values[k] = 0.0;
  for (int k : buffers.pinnedDiagonal)
    if (!(values[k] > 0.0))
      values[k] = 1.0;
  if (timings)
    (*timings)[Stage::Assembly].ms += clock.lapMs();
  // The single-precision factor straight from the tangent: about half the time of the double
  // factor and its copy. Where single precision breaks down on the tangent, from the double factor,
  // which also gives the message when the tangent is not positive definite.
  FactorReuse reuse;
  if (keepRest && fp.reuseTolerance >= 0.0)
    reuse.keep = keepRest;
  if (reusing) {
    reuse.from = &fp.rest;
    reuse.tolerance = fp.reuseTolerance;
  }
  const bool factoredSingle =
      singlePrecision &&
      made->single.factorize(fp.analysis, factored, 2, &buffers.workspace, buffers.values, reuse)
          .ok;
  Status status = Status::Ok();
  if (!factoredSingle) {
    status = made->factor.analyzeLike(fp.analysis);
    if (status)
      status = made->factor.factorize(factored);
    if (status && singlePrecision)
      status = made->single.assign(made->factor);
  }
  if (timings)
    (*timings)[Stage::Factorization].ms += clock.lapMs();
  if (!status)
    return status;
  if (backend && singlePrecision) {
    std::unique_ptr<FactorOnDevice> device;
    const Status copied = backend->makeFactorOnDevice(made->single, made->tangent, device);
    if (copied)
      made->device = std::move(device);
    else
      made->deviceError = copied.message;
  }
  out = std::move(made);
  return Status::Ok();
}

// The state ahead of a drag corrected by one Newton step with the factor made there (`ahead`,
// whose state, force and contact are the extrapolated state's; `values`: the targets and loads
// extrapolated there), and the tangent factored again where that step leads. The predictor of the
// next drag step is a Newton step from the factor's state, which starts nearer the equilibrium from
// the corrected state. False (ahead stays) when the step does not lower the residual, inverts a
// cell, or the tangent there is not positive definite.
Status CorrectAhead(const Structure& st, const FactorPattern& fp, TangentBuffers& buffers,
                    const TangentFactor& ahead, Problem values, bool contact, bool singlePrecision,
                    ComputeBackend* backend, std::shared_ptr<TangentFactor>& out) {
  values.prescribed = ahead.prescribed;
  Evaluation at;
  at.force = ahead.force;
  const Balance before = BalanceOf(values, at, ahead.state, 1.0);
  Eigen::VectorXd step;
  if (Status solved = SolveOnCpu(ahead, singlePrecision, before.residual, step); !solved)
    return solved;
  ZeroPrescribed(ahead.prescribed, step);
  const Eigen::VectorXd next = ahead.state - step;
  std::shared_ptr<TangentFactor> made;
  if (Status s = FactorTangent(st, fp, buffers, next, ahead.prescribed, contact ? &values : nullptr,
                               singlePrecision, backend, made, nullptr);
      !s)
    return s;
  values.prescribed = made->prescribed;
  at.force = made->force;
  if (!(BalanceOf(values, at, next, 1.0).residualNorm < before.residualNorm))
    return Status::Error("the Newton step from the state ahead did not lower its residual");
  out = std::move(made);
  return Status::Ok();
}

} // namespace

// How long the worker waits, once it has factored the tangent ahead of a drag, for the next edit
// before it corrects that state (PrecomputedLargeDeformationOptions::aheadCorrections): longer than
// the gap between two updates of a continuous drag in the GUI (about 0.1 s), shorter than a pause.
constexpr std::chrono::milliseconds kCorrectionPause(200);

class LargeDeformationSystem {
public:
  ~LargeDeformationSystem() { stopWorker(); }

  // Ends the background refactorization for good (joins the worker, which finishes a running
  // factorization first).
  void stopWorker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      pending_ = releasesPending_ = false;
    }
    wake_.notify_all();
    idle_.notify_all();
    releasesMade_.notify_all();
    if (worker_.joinable() && worker_.get_id() != std::this_thread::get_id())
      worker_.join();
  }

  PrecomputeRequest request;
  PrecomputedLargeDeformationOptions options;
  std::shared_ptr<Structure> structure;
  // The backend that runs the steps it can (options.useBackend), and its forces (null: the CPU's,
  // with why in forcesError when a backend was asked).
  std::shared_ptr<ComputeBackend> backend;
  std::unique_ptr<HyperelasticForces> forces;
  std::string forcesError;
  // The factored pattern's ordering and symbolic analysis, made once: every factorization copies
  // it (the pattern never changes; the contact only zeroes rows and columns).
  FactorPattern factorPattern;
  DofColumns movable;
  // The rest state's factor, kept for solves that start from rest (a move back towards zero is
  // nearer the rest state than the last converged one).
  std::shared_ptr<const TangentFactor> restFactor;
  StageTimings timings;

  std::shared_ptr<const TangentFactor> factor() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return factor_;
  }
  void setFactor(std::shared_ptr<const TangentFactor> f) {
    std::lock_guard<std::mutex> lock(mutex_);
    factor_ = std::move(f);
  }

  // Queues a refactorization at (u, prescribed); a newer request replaces a queued one.
  // ahead: a state to factor at instead, if no cell is inverted there (empty: none).
  // aheadValues: with lift-off, the targets and loads extrapolated to `ahead` (st null: none), for
  // the contact there: Newton's rule applied once at `ahead` gives the factor's contact, so that a
  // drag whose next step lifts a node off (or puts one back) finds it already in the factor.
  void requestRefactorization(const Eigen::VectorXd& u, const std::vector<char>& prescribed,
                              Eigen::VectorXd ahead = Eigen::VectorXd(),
                              Problem aheadValues = Problem(), bool contactAhead = false) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stop_)
        return;
      pendingU_ = u;
      pendingAhead_ = std::move(ahead);
      pendingAheadValues_ = std::move(aheadValues);
      pendingContactAhead_ = contactAhead;
      pendingPrescribed_ = prescribed;
      pending_ = true;
      startWorker();
    }
    wake_.notify_all();
  }

  void waitIdle() {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return (!pending_ && !releasesPending_ && !busy_) || stop_; });
  }
  int backgroundCount() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return backgroundCount_;
  }
  int aheadFailures() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return aheadFailures_;
  }
  int correctedCount() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return correctedCount_;
  }

  // Queues the rest factor's RestReleases.
  void requestRestReleases() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stop_)
        return;
      releasesPending_ = true;
      startWorker();
    }
    wake_.notify_all();
  }
  // Waits for them if they are queued or being made, so that a solve's path does not depend on
  // the worker's timing. Null where none were asked for or they could not be made.
  std::shared_ptr<const RestReleases> restReleases() const {
    std::unique_lock<std::mutex> lock(mutex_);
    releasesMade_.wait(lock, [this] { return (!releasesPending_ && !makingReleases_) || stop_; });
    return restReleases_;
  }

  // What a synchronous refactorization assembles into (the solve's thread only).
  TangentBuffers solveBuffers;

private:
  // With mutex_ held.
  void startWorker() {
    if (worker_.joinable())
      return;
    workerBuffers_.pattern = solveBuffers.pattern; // copied here: the solve's thread writes it
    workerBuffers_.values = solveBuffers.values;
    workerBuffers_.tangents = solveBuffers.tangents;
    worker_ = std::thread([this] { work(); });
  }

  void work() {
    NameThisThread("faceplan-drag");
    YieldToInteractiveWork();
    MarkThreadAsBackground();
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [this] { return stop_ || pending_ || releasesPending_; });
      if (stop_)
        return;
      if (releasesPending_) {
        releasesPending_ = false;
        busy_ = makingReleases_ = true;
        lock.unlock();
        std::shared_ptr<const RestReleases> made =
            MakeRestReleases(*restFactor, structure->liftOffDofs, options.maxRestReleases);
        lock.lock();
        restReleases_ = std::move(made);
        busy_ = makingReleases_ = false;
        releasesMade_.notify_all();
        if (!pending_)
          idle_.notify_all();
        continue; // a refactorization queued meanwhile
      }
      const Eigen::VectorXd u = std::move(pendingU_);
      const Eigen::VectorXd ahead = std::move(pendingAhead_);
      Problem aheadValues = std::move(pendingAheadValues_);
      const bool contactAhead = pendingContactAhead_;
      const std::vector<char> prescribed = std::move(pendingPrescribed_);
      pending_ = false;
      busy_ = true;
      lock.unlock();
      std::shared_ptr<TangentFactor> made;
      // A tangent that is not positive definite keeps the previous factor.
      Status status = Status::Error("no state ahead");
      if (ahead.size() == u.size())
        status = FactorTangent(*structure, factorPattern, workerBuffers_, ahead, prescribed,
                               contactAhead ? &aheadValues : nullptr, options.singlePrecisionFactor,
                               backend.get(), made, nullptr);
      const bool refusedAhead = ahead.size() == u.size() && !status.ok;
      if (!status)
        status = FactorTangent(*structure, factorPattern, workerBuffers_, u, prescribed, nullptr,
                               options.singlePrecisionFactor, backend.get(), made, nullptr);
      lock.lock();
      if (refusedAhead)
        ++aheadFailures_;
      if (status) {
        factor_ = made;
        ++backgroundCount_;
      }
      // The state ahead corrected by Newton steps and factored again, in a pause: a drag that
      // goes on takes the factor just made (on two cores the correction beside the next edits'
      // solves and rendering cost the GUI's drag a fifth of its updates), and a surgeon who
      // pauses gets the next step's predictor from the corrected state.
      const bool correct = status && ahead.size() == u.size() && !refusedAhead &&
                           options.aheadCorrections > 0 && aheadValues.st;
      if (correct)
        wake_.wait_for(lock, kCorrectionPause,
                       [this] { return stop_ || pending_ || releasesPending_; });
      // Each correction takes a Newton step from the last factor's state and factors there; the
      // next edit, or a step that does not lower the residual, ends them.
      for (int round = 0;
           round < options.aheadCorrections && correct && !pending_ && !releasesPending_ && !stop_;
           ++round) {
        lock.unlock();
        std::shared_ptr<TangentFactor> corrected;
        const bool ok =
            CorrectAhead(*structure, factorPattern, workerBuffers_, *made, aheadValues,
                         contactAhead, options.singlePrecisionFactor, backend.get(), corrected)
                .ok;
        lock.lock();
        if (!ok || pending_)
          break;
        made = corrected;
        factor_ = std::move(corrected);
        ++correctedCount_;
      }
      busy_ = false;
      if (!pending_ && !releasesPending_)
        idle_.notify_all();
    }
  }

  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::thread worker_;
  std::shared_ptr<const TangentFactor> factor_;
  TangentBuffers workerBuffers_; // the worker's only
  Eigen::VectorXd pendingU_, pendingAhead_;
  Problem pendingAheadValues_;
  bool pendingContactAhead_ = false;
  std::vector<char> pendingPrescribed_;
  bool pending_ = false, busy_ = false, stop_ = false, releasesPending_ = false,
       makingReleases_ = false;
  mutable std::condition_variable releasesMade_;
  std::shared_ptr<const RestReleases> restReleases_;
  int backgroundCount_ = 0;
  int aheadFailures_ = 0;  // states ahead that could not be factored (the converged one was)
  int correctedCount_ = 0; // states ahead corrected by a Newton step
};

namespace {

// Two successive drag changes of the prescribed values that differ by at most this fraction make a
// steady drag, which is extrapolated to second order.
constexpr double kSteadyDrag = 0.1;

Status ValidateOptions(const PrecomputedLargeDeformationOptions& o) {
  if (!(o.tolerance > 0.0) || !(o.settleTolerance > 0.0) || !(o.recheckTolerance >= 0.0) ||
      !(o.refactorCostIterations >= 0.0) || !(o.refactorCostIterationsOnDevice >= 0.0) ||
      o.historySize < 0 || o.maxIterations < 1 || o.refactorAfter < 0 ||
      o.maxRefactorizations < 0 || o.maxSubstepHalvings < 0 || o.maxContactUpdates < 0 ||
      o.maxCoupledReleases < 0 || o.maxRestReleases < 0 || o.factorAheadOrder < 1 ||
      o.factorAheadOrder > 2 || o.aheadCorrections < 0 || std::isnan(o.reuseTolerance))
    return Status::Error("invalid large-deformation options");
  return Status::Ok();
}

// The whole mesh's tangent pattern `upper` without the couplings of the nodes that every solve
// pins.
void MakeFactorPattern(const Structure& st, const SparseMatrix& upper, FactorPattern& fp) {
  std::vector<char> pinned(static_cast<size_t>(st.n), 1);
  for (size_t d = 0; d < st.prescribed.size(); ++d)
    if (!st.prescribed[d])
      pinned[d / 3] = 0;
  for (int d : st.liftOffDofs)
    pinned[d / 3] = 0;
  const int n = static_cast<int>(upper.cols());
  std::vector<int> start(static_cast<size_t>(n) + 1, 0), row;
  fp.source.clear();
  for (int col = 0; col < n; ++col) {
    for (int k = upper.outerIndexPtr()[col]; k < upper.outerIndexPtr()[col + 1]; ++k) {
      const int r = upper.innerIndexPtr()[k];
      if (r == col || (!pinned[r / 3] && !pinned[col / 3])) {
        row.push_back(r);
        fp.source.push_back(k);
      }
    }
    start[col + 1] = static_cast<int>(row.size());
  }
  fp.upper = SparseMatrix(n, n);
  fp.upper.reserve(static_cast<Eigen::Index>(row.size()));
  for (int col = 0; col < n; ++col) {
    fp.upper.startVec(col);
    for (int k = start[col]; k < start[col + 1]; ++k)
      fp.upper.insertBack(row[k], col) = 0.0;
  }
  fp.upper.finalize();
}

// The structure's cells in the backend's plain arrays.
HyperelasticCells CellsOf(const Structure& st) {
  HyperelasticCells c;
  const TetMesh& mesh = *st.mesh;
  const size_t m = static_cast<size_t>(mesh.numTets());
  c.nodes = static_cast<int>(st.n);
  c.corners.resize(4 * m);
  c.gradients.resize(12 * m);
  c.volume.resize(m);
  c.mu.resize(m);
  c.kappa.resize(m);
  c.smallStrain = st.smallStrain;
  for (size_t e = 0; e < m; ++e) {
    for (int a = 0; a < 4; ++a) {
      c.corners[4 * e + a] = mesh.tets(static_cast<Eigen::Index>(e), a);
      for (int j = 0; j < 3; ++j)
        c.gradients[12 * e + 3 * a + j] = st.cells[e].gradients(a, j);
    }
    c.volume[e] = st.cells[e].volume;
    c.mu[e] = st.materials[e].mu;
    c.kappa[e] = st.materials[e].kappa;
  }
  c.frameOf = st.frameOf;
  c.frames.reserve(9 * st.frames.size());
  for (const Eigen::Matrix3d& q : st.frames)
    c.frames.insert(c.frames.end(), q.data(), q.data() + 9);
  return c;
}

Status PrecomputeImpl(const PrecomputeRequest& request,
                      const PrecomputedLargeDeformationOptions& options,
                      std::shared_ptr<LargeDeformationSystem>& out) {
  StageClock total, clock;
  out.reset();
  if (request.options.elementOrder != ElementOrder::Linear)
    return Status::Error("the large-deformation model supports linear (4-node) elements only");
  Status status = ValidateOptions(options);
  if (!status)
    return status;
  status = ValidateSolveInputs(request.mesh, request.materials, request.sets);
  if (!status)
    return status;
  auto sys = std::make_shared<LargeDeformationSystem>();
  sys->request = request;
  sys->request.options.backend.reset();
  if (options.useBackend && options.singlePrecisionFactor && request.options.backend)
    sys->backend = request.options.backend;
  sys->options = options;
  sys->solveBuffers.values = std::make_shared<FactorValueBin>();
  sys->solveBuffers.tangents = std::make_shared<TangentBin>();
  sys->structure = std::make_shared<Structure>();
  Structure& st = *sys->structure;
  status = MakeStructure(sys->request, options.slidingLiftOff, st);
  if (status)
    status = MakePattern(st, sys->solveBuffers.pattern);
  if (!status)
    return status;
  if (sys->backend) {
    const Status made = sys->backend->makeHyperelasticForces(CellsOf(st), sys->forces);
    if (!made) {
      sys->forces.reset();
      sys->forcesError = made.message;
    }
  }
  sys->timings[Stage::Separation].ms = clock.lapMs();
  MakeFactorPattern(st, sys->solveBuffers.pattern.upper, sys->factorPattern);
  FillReducingOrdering ordering;
  status = OrderNodesWithTrailing(sys->factorPattern.upper, 3, {}, ordering);
  if (status)
    status = sys->factorPattern.analysis.analyze(sys->factorPattern.upper, &ordering);
  if (!status)
    return status;
  sys->timings[Stage::Reordering].ms = clock.lapMs();
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(3 * st.n);
  std::shared_ptr<TangentFactor> factor;
  sys->factorPattern.reuseTolerance = options.reuseTolerance;
  status = FactorTangent(st, sys->factorPattern, sys->solveBuffers, rest, st.prescribed, nullptr,
                         options.singlePrecisionFactor, sys->backend.get(), factor, &sys->timings,
                         &sys->factorPattern.rest);
  if (!status)
    return Status::Error("the large-deformation precompute could not factor the rest tangent: " +
                         status.message);
  if (sys->factorPattern.rest.made()) {
    FactorPattern& fp = sys->factorPattern;
    fp.restPacked = sys->solveBuffers.packed;
    sys->solveBuffers.restHeld.assign(static_cast<size_t>(st.mesh->numTets()), 1);
    fp.restFactor = factor;
    fp.packedEntry = PackedEntries(sys->solveBuffers.pattern, fp.restPacked.size());
  }
  // The rest tangent (upper, unpinned) stays in restFactor.
  std::vector<int> movableDofs;
  for (int node : request.sets.movable)
    for (int j = 0; j < 3; ++j)
      movableDofs.push_back(3 * node + j);
  sys->movable = DofColumns(factor->tangent, std::move(movableDofs));
  st.unitStrainForce = RestForceNorm(factor->tangent, LocalPositions(st));
  sys->restFactor = factor;
  sys->setFactor(std::move(factor));
  // About as long again as the rest of the precompute: on the worker thread, which the first
  // move from rest rarely overtakes (a solve that needs it waits for it).
  if (!st.liftOffDofs.empty() && options.singlePrecisionFactor && options.coupleRestReleases)
    sys->requestRestReleases();
  sys->timings[Stage::Total].ms = total.elapsedMs();
  out = std::move(sys);
  return Status::Ok();
}

// Why a sub-step failed: a smaller one may mend it, or the solve falls back.
enum class Failure { None, Smaller, Fallback, Stopped };

class QuasiNewton {
public:
  QuasiNewton(LargeDeformationSystem& sys, Problem& pb, PrecomputedLargeDeformationReport& report,
              StageTimings& timings, std::shared_ptr<const TangentFactor> factor)
      : sys_(sys), st_(*sys.structure), pb_(pb), report_(report), timings_(timings),
        factor_(std::move(factor)), history_(sys.options.historySize) {}
  QuasiNewton(const QuasiNewton&) = delete;
  QuasiNewton& operator=(const QuasiNewton&) = delete;

  std::string why;        // set with Failure::Fallback
  int iterationLimit = 0; // > 0: Failure::Stopped when reached

  // From u (converged for the previous targets, with pb_.prescribed's contact) to equilibrium at
  // pb_'s targets and loads.
  Failure substep(Eigen::VectorXd& u) {
    clearHistory();
    sinceFactor_ = 0;
    if (!predict(u))
      return Failure::Smaller;
    const bool liftOff = !st_.liftOffDofs.empty();
    const double tight = sys_.options.tolerance;
    const double settle = sys_.options.settleTolerance;
    double tolerance = liftOff ? std::max(tight, settle) : tight;
    bool rechecking = false; // at recheckTolerance, on the way to the tolerance
    int updates = 0;
    while (true) {
      // Whether a refactorization pays is judged against reaching the solve's own tolerance once
      // the contact holds, and from rest also while it settles: a solve from rest starts far
      // from its answer, and a factor made on the way serves the rest of it (the BSSO with open
      // lips: 14 iterations against 22). A warm start begins near its answer with a factor made
      // there; judged so while its contact settles, it factored where that did not pay (a step
      // back in a drag: 154 iterations and 4 factorizations against 12 and none).
      const bool wholeWay = rechecking || !report_.warmStarted;
      const Failure f = minimise(u, tolerance, wholeWay ? tight : tolerance);
      if (f != Failure::None)
        return f;

      const std::vector<char> before = pb_.prescribed;
      const bool changed = UpdateContact(pb_, u, 1.0, &lastForce_);
      if (!changed && tolerance == tight)
        return Failure::None;
      bool moved = false;
      if (changed) {
        ++report_.contactUpdates;
        if (++updates > sys_.options.maxContactUpdates) {
          why = "the lift-off contact did not settle";
          return Failure::Smaller;
        }
        for (int dof : st_.liftOffDofs)
          if (pb_.prescribed[dof] && !before[dof] && u[dof] != pb_.target[dof]) {
            u[dof] = pb_.target[dof];
            moved = true;
          }
        clearHistory();
        tolerance = std::max(tight, settle);
        rechecking = false;
      } else {
        const double recheck = sys_.options.recheckTolerance;
        rechecking = recheck > tight && tolerance > recheck;
        tolerance = rechecking ? recheck : tight;
      }
      if (!moved) { // the converged evaluation still holds at u
        cached_.energy = lastEnergy_;
        cached_.force = lastForce_;
        haveCached_ = true;
      }
    }
  }

  double lastResidual() const { return lastResidual_; }
  // The internal force at the first sub-step's start (a converged state's), when known.
  void setStartForce(const Eigen::VectorXd* force) { startForce_ = force; }
  Eigen::VectorXd takeLastForce() { return std::move(lastForce_); }

private:
  bool evaluate(const Eigen::VectorXd& u, Evaluation& ev) {
    StageClock clock;
    ++report_.evaluations;
    bool ok = false, onDevice = false;
    if (sys_.forces && !forcesFailed_) {
      const Status s = sys_.forces->evaluate(u, ev.energy, ev.force, ok);
      if (s) {
        onDevice = true;
        ++report_.deviceEvaluations;
      } else {
        forcesFailed_ = true; // the CPU's from here on in this solve
        noteDevice("the forces: " + s.message);
      }
    }
    if (!onDevice)
      ok = Evaluate(st_, u, ev, nullptr, &scratch_);
    timings_[Stage::ElementStiffness].ms += clock.lapMs();
    return ok;
  }

  // H0 r: P F^-1 P r, with the DOFs that lift-off has freed since the factor was made coupled
  // back in where there is a coupling (see prepareReleased).
  Eigen::VectorXd applyFactor(const Eigen::VectorXd& r) {
    prepareReleased();
    const ReleaseCoupling& c = released_.coupling;
    if (c.dofs.empty())
      return substitute(r);
    Eigen::VectorXd b = r;
    for (int d : c.dofs)
      b[d] = 0.0;
    Eigen::VectorXd x = substitute(b);
    if (x.size() == 0)
      return x;
    Eigen::VectorXd xr(static_cast<Eigen::Index>(c.dofs.size()));
    for (size_t k = 0; k < c.dofs.size(); ++k)
      xr[k] = r[c.dofs[k]];
    // A_R's rows of R are zero, and tangentProduct reads them as x's rows of R. The substitution
    // leaves those rows zero (the factor pins them and b is zero there); this does not rely on it.
    for (int d : c.dofs)
      x[d] = 0.0;
    xr -= c.tangentProduct(x);
    xr = c.schur.solve(xr);
    c.subtractProduct(xr, x);
    for (size_t k = 0; k < c.dofs.size(); ++k)
      x[c.dofs[k]] = xr[k];
    return x;
  }

  // Lift-off DOFs free now but pinned in the factor (R) have only their diagonal there, decoupled
  // from the rest: the initial Hessian would miss their coupling and L-BFGS would need many
  // iterations to learn it. The inverse of the tangent with them free is exact through their
  // Schur complement: with G = P F^-1 P and A_R the factor state's tangent columns of R (their
  // pinned and R rows zeroed), W = G A_R and S = A_RR - A_R^T W, H0 [b; b_R] = [G b - W x_R; x_R]
  // with x_R = S^-1 (b_R - A_R^T G b). For the rest factor W and S of every lift-off DOF are made
  // once (RestReleases): while the contact differs from the rest's by releases only, R's are their
  // columns and block, whatever R is (the rows zeroed are the rest factor's pinned ones either
  // way). With another factor R's columns are substituted (all at once) once per contact change,
  // for a few DOFs only.
  void prepareReleased() {
    if (released_.factor == factor_.get() && released_.prescribed == pb_.prescribed)
      return;
    released_.coupling.clear();
    released_.factor = factor_.get();
    released_.prescribed = pb_.prescribed;
    if (factor_->prescribed.size() != pb_.prescribed.size())
      return;
    std::vector<int> dofs = freedSinceFactor(pb_.prescribed);
    if (dofs.empty())
      return;
    const Eigen::Index n = pb_.prescribed.size(), k = static_cast<Eigen::Index>(dofs.size());
    Eigen::MatrixXd schur(k, k);
    ReleaseCoupling& c = released_.coupling;
    c.n = n;
    c.values = factor_->tangent.valuePtr();
    if (const std::shared_ptr<const RestReleases> rest = restReleasesFor(dofs)) {
      c.set = std::shared_ptr<const DofColumns>(rest, &rest->tangentColumns);
      for (Eigen::Index j = 0; j < k; ++j) {
        const int column = rest->column[dofs[j]];
        c.w.push_back(rest->w.col(column).data());
        c.setColumn.push_back(column);
        for (Eigen::Index i = 0; i < k; ++i)
          schur(i, j) = rest->schur(rest->column[dofs[i]], column);
      }
    } else {
      if (k > sys_.options.maxCoupledReleases)
        return;
      auto set = std::make_shared<DofColumns>(factor_->tangent, dofs);
      Eigen::MatrixXd columns, w;
      ReleasedColumns(*factor_, pb_.prescribed, *set, columns, schur);
      if (!substituteMany(columns, w))
        return;
      schur -= columns.transpose() * w;
      c.own.resize(static_cast<size_t>(n * k));
      Eigen::Map<Eigen::MatrixXf>(c.own.data(), n, k) = w.cast<float>();
      for (Eigen::Index j = 0; j < k; ++j) {
        c.w.push_back(c.own.data() + j * n);
        c.setColumn.push_back(static_cast<int>(j));
      }
      c.set = std::move(set);
    }
    schur = 0.5 * (schur + schur.transpose()).eval();
    c.schur.compute(schur);
    if (c.schur.info() != Eigen::Success) {
      c.clear(); // not positive definite (the factor's state is far): the diagonal
      return;
    }
    c.dofs = std::move(dofs);
  }

  // The lift-off DOFs free in `prescribed` but pinned in the present factor.
  std::vector<int> freedSinceFactor(const std::vector<char>& prescribed) const {
    std::vector<int> freed;
    for (int d : st_.liftOffDofs)
      if (factor_->prescribed[d] && !prescribed[d])
        freed.push_back(d);
    return freed;
  }

  // The rest factor's RestReleases, when the factor is the rest factor, they are made, and the
  // contact differs from the rest's by releases only.
  std::shared_ptr<const RestReleases> restReleasesFor(const std::vector<int>& dofs) const {
    if (factor_ != sys_.restFactor)
      return nullptr;
    std::shared_ptr<const RestReleases> rest = sys_.restReleases();
    if (!rest)
      return nullptr;
    for (int d : dofs)
      if (rest->column[d] < 0)
        return nullptr;
    for (size_t i = 0; i < pb_.prescribed.size(); ++i)
      if (pb_.prescribed[i] && !factor_->prescribed[i])
        return nullptr;
    return rest;
  }

  // P F^-1 P r for every column r of `rhs`: from four columns on with the single-precision factor
  // read once for all of them (its blocked products have a fixed cost of about three single
  // substitutions), else column by column. False when a substitution failed.
  bool substituteMany(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& out) {
    constexpr Eigen::Index kAtOnce = 4;
    if (rhs.cols() >= kAtOnce && !factor_->device && sys_.options.singlePrecisionFactor) {
      StageClock clock;
      const bool solved = factor_->single.solve(rhs, out).ok;
      report_.factorSolves += static_cast<int>(rhs.cols());
      timings_[Stage::Solve].ms += clock.lapMs();
      if (!solved)
        return false;
      for (Eigen::Index j = 0; j < out.cols(); ++j)
        ZeroPrescribed(pb_.prescribed, out.col(j));
      return true;
    }
    out.resize(rhs.rows(), rhs.cols());
    for (Eigen::Index j = 0; j < rhs.cols(); ++j) {
      const Eigen::VectorXd x = substitute(rhs.col(j));
      if (x.size() == 0)
        return false;
      out.col(j) = x;
    }
    return true;
  }

  // P F^-1 P r.
  Eigen::VectorXd substitute(const Eigen::VectorXd& r) {
    StageClock clock;
    Eigen::VectorXd out;
    Status solved = Status::Error("no device");
    if (factor_->device) {
      solved = factor_->device->solve(r, out);
      if (solved)
        ++report_.deviceSubstitutions;
      else
        noteDevice("a substitution: " + solved.message);
    } else if (sys_.backend) {
      noteDevice("the substitutions: " + factor_->deviceError);
    }
    if (!solved)
      solved = SolveOnCpu(*factor_, sys_.options.singlePrecisionFactor, r, out);
    ++report_.factorSolves;
    timings_[Stage::Solve].ms += clock.lapMs();
    if (!solved)
      return Eigen::VectorXd();
    ZeroPrescribed(pb_.prescribed, out);
    return out;
  }

  // The prescribed DOFs go to their targets and the free ones follow the factored tangent. From the
  // factor's own state when its prescribed values are nearer the targets than u's (a drag's
  // factor, made one step ahead): the predictor is then Newton's step there.
  bool predict(Eigen::VectorXd& u) {
    if (factor_->state.size() == u.size() && sameExceptLiftOff(factor_->prescribed)) {
      double fromU = 0.0, fromFactor = 0.0;
      const double* target = pb_.target.data();
      const double* from = u.data();
      const double* state = factor_->state.data();
      const char* pinned = pb_.prescribed.data();
      const char* pinnedThere = factor_->prescribed.data();
      for (Eigen::Index i = 0; i < u.size(); ++i) { // selects, not branches (see the move below)
        const double du = target[i] - from[i], df = target[i] - state[i];
        const bool read = pinned[i] || pinnedThere[i];
        fromU += read ? du * du : 0.0;
        fromFactor += read ? df * df : 0.0;
      }
      // From the factor's state with the factor's contact (the contact predicted there, for a
      // factor made ahead): the contact updates that follow settle whatever it got wrong.
      if (fromFactor < fromU) {
        u = factor_->state;
        startForce_ = &factor_->force;
        pb_.prescribed = factor_->prescribed;
      }
    }
    const Eigen::Index n = u.size();
    Eigen::VectorXd move(n);
    double largestMove = 0.0, largestTarget = 0.0;
    {
      // Every operand read whatever the mask, so that the mask selects instead of branching (the
      // prescribed DOFs lie among the free ones without a pattern a branch predictor could learn).
      const double* target = pb_.target.data();
      const double* from = u.data();
      const char* pinned = pb_.prescribed.data();
      double* to = move.data();
      for (Eigen::Index i = 0; i < n; ++i) {
        const double d = target[i] - from[i];
        const double m = pinned[i] ? d : 0.0;
        const double am = std::abs(m), at = std::abs(target[i]);
        to[i] = m;
        largestMove = am > largestMove ? am : largestMove;
        largestTarget = at > largestTarget ? at : largestTarget;
      }
    }
    Evaluation ev;
    const Eigen::VectorXd* force = &ev.force;
    const bool known = startForce_ && startForce_->size() == n;
    if (known) {
      force = startForce_; // the converged state's own
    } else if (!evaluate(u, ev)) {
      return false;
    }
    startForce_ = nullptr;
    // A start that is already the equilibrium of these targets and loads (an update that changed
    // nothing the solve reads) stays where it is: a step from it would move it within the
    // tolerance, and the same input would give another result each time.
    if (largestMove == 0.0) {
      Evaluation at;
      at.force = *force; // the residual's; the energy is not read here
      const Balance b = BalanceOf(pb_, at, u, 1.0);
      if (b.residualNorm <= sys_.options.tolerance * b.scale) {
        if (!known) {
          cached_ = std::move(ev);
          haveCached_ = true;
        }
        return true;
      }
    }
    // From a factor made where the drag leads, the prescribed values are already at their targets
    // to round-off: the tangent's product with that move is skipped (the move itself is applied;
    // the predictor only starts the iterations, whose residual decides convergence).
    Eigen::VectorXd product;
    if (largestMove > 1e-12 * largestTarget) {
      Status multiplied = Status::Error("no device");
      if (factor_->device && !(multiplied = factor_->device->multiply(move, product)))
        noteDevice("a tangent product: " + multiplied.message);
      if (!multiplied && !movableProduct(move, product))
        product = factor_->tangent.selfadjointView<Eigen::Upper>() * move;
    }
    // -(f - f_ext + K move) on the free DOFs.
    Eigen::VectorXd rhs(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double r = (*force)[i] - pb_.externalLoad[i];
      const double free = -(product.size() ? r + product[i] : r);
      rhs[i] = pb_.prescribed[i] ? 0.0 : free;
    }
    Eigen::VectorXd follow = applyFactor(rhs);
    if (follow.size() == 0 || !follow.allFinite())
      return false;
    Eigen::VectorXd trial;
    for (double alpha : {1.0, 0.5, 0.25, 0.0}) {
      trial = u + move + alpha * follow;
      if (evaluate(trial, cached_)) {
        u.swap(trial);
        haveCached_ = true;
        return true;
      }
    }
    return false;
  }

  // K move through the movable DOFs' columns alone, when the move lies on them (a bone's move; a
  // lift-off DOF pinned again moves elsewhere): the whole tangent's product reads every entry.
  bool movableProduct(const Eigen::VectorXd& move, Eigen::VectorXd& product) const {
    if (factor_->tangent.nonZeros() != sys_.restFactor->tangent.nonZeros())
      return false;
    for (Eigen::Index i = 0; i < move.size(); ++i)
      if (move[i] != 0.0 && !sys_.movable.has[i])
        return false;
    sys_.movable.multiply(factor_->tangent.valuePtr(), move, product);
    return true;
  }

  // Whether `prescribed` pins what pb_ pins, lift-off's DOFs aside.
  bool sameExceptLiftOff(const std::vector<char>& prescribed) const {
    if (prescribed.size() != pb_.prescribed.size())
      return false;
    std::vector<char> mine = pb_.prescribed;
    for (int d : st_.liftOffDofs)
      mine[d] = prescribed[d];
    return mine == prescribed;
  }

  void clearHistory() {
    history_.clear();
    phase_.clear();
  }

  // Factors the tangent at u. With lift-off, the lift-off DOFs that Newton's rule releases at u
  // (force: the internal force there) are released first and factored free: the contact found at
  // the last settle is a looser state's, and a DOF it would release after the factorization would
  // be pinned in the new factor. The first time in a solve that the present factor is the rest
  // factor, whose coupling takes any release exactly, the release is made without the
  // factorization: the slow convergence may have been the contact's, and the rate is measured
  // again. True when the factor or the contact changed; `released`: whether the contact changed
  // (the caller's residual then changes too).
  bool refactor(const Eigen::VectorXd& u, const Eigen::VectorXd& force, bool& released) {
    released = false;
    if (report_.refactorizations >= sys_.options.maxRefactorizations)
      return false;
    std::vector<char> prescribed = pb_.prescribed;
    if (!st_.liftOffDofs.empty()) {
      Problem rule = pb_;
      if (UpdateContact(rule, u, 1.0, &force))
        for (int d : st_.liftOffDofs)
          if (prescribed[d] && !rule.prescribed[d]) {
            prescribed[d] = 0;
            released = true;
          }
    }
    if (released && !releasedInsteadOfFactoring_ && restReleasesFor(freedSinceFactor(prescribed))) {
      releasedInsteadOfFactoring_ = true;
      pb_.prescribed = std::move(prescribed);
      ++report_.contactUpdates;
      return true;
    }
    std::shared_ptr<TangentFactor> made;
    const bool factored =
        FactorTangent(st_, sys_.factorPattern, sys_.solveBuffers, u, prescribed, nullptr,
                      sys_.options.singlePrecisionFactor, sys_.backend.get(), made, &timings_)
            .ok;
    if (!factored) {
      released = false;
      return false;
    }
    if (made->single.factoredShare() < 1.0)
      ++report_.partialRefactorizations;
    factor_ = std::move(made);
    ++report_.refactorizations;
    if (released) {
      pb_.prescribed = std::move(prescribed);
      ++report_.contactUpdates;
    }
    return true;
  }

  // Whether factoring the tangent here now costs less than the iterations that the last few
  // iterations' rate of convergence predicts with the present factor (it converges slowly where
  // the present factor's state is far from u). After a factor at u the rest of the way still takes
  // a few iterations (kAfterFactor). The factorization's cost is a fixed number of iterations, not
  // a timing, so that the same input gives the same result on every run.
  // `residual` is the last of phase_.
  bool refactorPays(double residual, double goal) const {
    constexpr int kRateSpan = 4;
    constexpr double kAfterFactor = 3.0;
    if (!sys_.options.adaptiveRefactorization || adaptiveFailed_ ||
        static_cast<int>(phase_.size()) <= kRateSpan ||
        report_.refactorizations >= sys_.options.maxRefactorizations)
      return false;
    const double before = phase_[phase_.size() - 1 - kRateSpan];
    const double rate = std::pow(residual / before, 1.0 / kRateSpan);
    const double left = rate < 1.0 ? std::log(goal / residual) / std::log(rate)
                                   : std::numeric_limits<double>::infinity();
    const double cost = factor_->device ? sys_.options.refactorCostIterationsOnDevice
                                        : sys_.options.refactorCostIterations;
    return left - kAfterFactor > cost;
  }

  // L-BFGS on the free DOFs with the current contact, to `tolerance`; whether a refactorization
  // pays is judged against reaching `goal` (the tolerance the solve goes on to).
  Failure minimise(Eigen::VectorXd& u, double tolerance, double goal) {
    Evaluation ev;
    if (haveCached_) {
      ev = std::move(cached_);
      haveCached_ = false;
    } else if (!evaluate(u, ev)) {
      return Failure::Smaller;
    }
    Balance b = BalanceOf(pb_, ev, u, 1.0);
    // The trial state, its evaluation and balance, and the new L-BFGS pair: their memory is kept
    // from iteration to iteration (swapped with the accepted state's, the oldest pair's reused).
    Eigen::VectorXd trial, d;
    Evaluation tev;
    Balance tb;
    while (true) {
      lastResidual_ = b.scale > 0.0 ? b.residualNorm / b.scale : 0.0;
      report_.convergence.emplace_back(clock_.elapsedMs(), lastResidual_);
      if (b.residualNorm <= tolerance * b.scale) {
        lastEnergy_ = ev.energy;
        lastForce_ = std::move(ev.force);
        return Failure::None;
      }
      if (iterationLimit > 0 && report_.iterations >= iterationLimit)
        return Failure::Stopped;
      if (report_.iterations >= sys_.options.maxIterations) {
        why = "it did not converge within " + std::to_string(sys_.options.maxIterations) +
              " quasi-Newton iterations";
        return Failure::Fallback;
      }
      ++report_.iterations;
      phase_.push_back(b.residualNorm);
      const bool due =
          sys_.options.refactorAfter > 0 && ++sinceFactor_ >= sys_.options.refactorAfter;
      const bool pays = !due && refactorPays(b.residualNorm, goal * b.scale);
      if (due || pays) {
        sinceFactor_ = 0;
        bool released = false;
        if (refactor(u, ev.force, released)) {
          clearHistory();
          if (released) {
            b = BalanceOf(pb_, ev, u, 1.0);
            phase_.assign(1, b.residualNorm);
          }
        } else if (pays)
          adaptiveFailed_ = true; // not positive definite here: the present factor goes on
      }
      bool accepted = false;
      for (int attempt = 0; attempt < 2 && !accepted; ++attempt) {
        history_.direction(
            b.residual, [this](const Eigen::VectorXd& q) { return applyFactor(q); }, d);
        if (d.size() == 0 || !d.allFinite()) {
          why = "a substitution with the factor failed";
          return Failure::Fallback;
        }
        const double slope = b.residual.dot(d);
        if (!(slope < 0.0)) {
          clearHistory();
          continue;
        }
        for (double alpha = 1.0; alpha >= 1.0 / 1024.0; alpha *= 0.5) {
          trial = u + alpha * d;
          if (!evaluate(trial, tev))
            continue; // a cell would invert: a shorter step
          BalanceInto(pb_, tev, trial, 1.0, tb);
          if (tb.potential <= b.potential + 1e-4 * alpha * slope ||
              tb.residualNorm < b.residualNorm) {
            history_.add(trial, u, tb.residual, b.residual);
            u.swap(trial);
            std::swap(b, tb);
            std::swap(ev, tev);
            accepted = true;
            break;
          }
        }
        if (!accepted)
          clearHistory(); // the factor's own step next
      }
      if (!accepted) {
        why = "its line search found no step that lowers the energy or the residual";
        return Failure::Smaller;
      }
    }
  }

  // A step the backend was asked for and did not take, once per solve.
  void noteDevice(const std::string& what) {
    if (report_.deviceNote.empty())
      report_.deviceNote = "the CPU ran " + what;
  }

  LargeDeformationSystem& sys_;
  const Structure& st_;
  Problem& pb_;
  PrecomputedLargeDeformationReport& report_;
  StageTimings& timings_;
  std::shared_ptr<const TangentFactor> factor_;
  EvaluationScratch scratch_;
  LbfgsHistory history_;
  struct ReleasedDofs {
    const TangentFactor* factor = nullptr;
    std::vector<char> prescribed; // the contact it was prepared for
    ReleaseCoupling coupling;
  } released_;
  int sinceFactor_ = 0;
  bool releasedInsteadOfFactoring_ = false; // see refactor()
  std::vector<double> phase_;               // residual norms since the history was last cleared
  bool adaptiveFailed_ = false;
  bool forcesFailed_ = false;
  double lastResidual_ = 0.0;
  Evaluation cached_; // the predictor's accepted state
  bool haveCached_ = false;
  const Eigen::VectorXd* startForce_ = nullptr;
  double lastEnergy_ = 0.0;   // at the last converged state
  Eigen::VectorXd lastForce_; // at the last converged state
  StageClock clock_;
};

Status SolveImpl(LargeDeformationSystem& sys, const SolveInput& input,
                 const LargeDeformationState* warm, SolveResult& result,
                 PrecomputedLargeDeformationReport& report, LargeDeformationState* converged,
                 int iterationLimit) {
  StageClock total;
  result = SolveResult();
  report = PrecomputedLargeDeformationReport();
  if (converged)
    *converged = LargeDeformationState();
  result.method = SolveMethod::LargeDeformationPrecomputed;
  result.backend = "CPU";
  const PrecomputeRequest& request = sys.request;
  if (input.movableDisplacement.rows() != static_cast<Eigen::Index>(request.sets.movable.size()))
    return Status::Error("expected one ROI displacement per movable node");
  if (!input.movableDisplacement.allFinite() || !input.gravity.allFinite())
    return Status::Error("prescribed displacements or loads contain NaN or infinite values");

  const Structure& st = *sys.structure;
  Problem pb;
  pb.st = sys.structure;
  Status status = SetValues(request, input, pb);
  if (!status)
    return status;
  // pb holds the whole move's targets and loads; a copy of them is made only for a sub-step short
  // of the whole move (each copy is a pass over the state's length).
  Eigen::VectorXd fullTarget, fullLoad;
  // The yardstick |K_0 u_prescribed| (the targets are zero off the movable nodes' DOFs).
  pb.linearForce = sys.movable.productNorm(sys.restFactor->tangent.valuePtr(), pb.target);

  Eigen::VectorXd u, rest;
  report.warmStarted = warm && warm->system == &sys && warm->u.size() == 3 * st.n &&
                       warm->target.size() == 3 * st.n && warm->load.size() == 3 * st.n;
  // From rest instead when the new targets and loads are nearer the rest state (zero) than the
  // warm state's: a move back towards the start is then a short solve with the rest factor.
  if (report.warmStarted) {
    double target = 0.0, targetChange = 0.0, load = 0.0, loadChange = 0.0; // squared norms
    for (Eigen::Index i = 0; i < 3 * st.n; ++i) {
      const double t = pb.target[i], dt = t - warm->target[i];
      const double l = pb.externalLoad[i], dl = l - warm->load[i];
      target += t * t;
      targetChange += dt * dt;
      load += l * l;
      loadChange += dl * dl;
    }
    if (target <= targetChange && load <= loadChange)
      report.warmStarted = false;
  }
  if (report.warmStarted) {
    u = warm->u;
    pb.prescribed = warm->prescribed;
  } else {
    u = rest = Eigen::VectorXd::Zero(3 * st.n);
    pb.prescribed = st.prescribed;
  }
  // Where the targets and loads go from (read only for a sub-step short of the whole move).
  const Eigen::VectorXd& fromTarget = report.warmStarted ? warm->target : rest;
  const Eigen::VectorXd& fromLoad = report.warmStarted ? warm->load : rest;

  if (iterationLimit < 0)
    return Status::Error("the quasi-Newton iteration limit must be 0 (none) or positive");
  if (sys.backend && !sys.forces)
    report.deviceNote = "the CPU ran the forces: " + sys.forcesError;
  report.setupMs = total.elapsedMs();
  QuasiNewton solver(sys, pb, report, result.timings,
                     report.warmStarted ? sys.factor() : sys.restFactor);
  solver.iterationLimit = iterationLimit;
  double reached = 0.0, step = 1.0;
  int halvings = 0;
  std::string why;
  while (reached < 1.0) {
    const double to = std::min(1.0, reached + step);
    if (to == 1.0) {
      if (fullTarget.size() != 0) { // after a sub-step short of the whole move
        pb.target = fullTarget;
        pb.externalLoad = fullLoad;
      }
    } else {
      if (fullTarget.size() == 0) {
        fullTarget = pb.target;
        fullLoad = pb.externalLoad;
      }
      pb.target = fromTarget + to * (fullTarget - fromTarget);
      pb.externalLoad = fromLoad + to * (fullLoad - fromLoad);
    }
    Eigen::VectorXd trial = u;
    const std::vector<char> contact = pb.prescribed;
    solver.why.clear();
    // The start's internal force where it is known: a warm start's, or the rest factor's (made at
    // the rest state, where a solve from rest starts).
    const Eigen::VectorXd* startForce = nullptr;
    if (reached == 0.0)
      startForce = report.warmStarted ? &warm->force : &sys.restFactor->force;
    solver.setStartForce(startForce);
    const Failure f = solver.substep(trial);
    if (f == Failure::Stopped) {
      if (to < 1.0)
        return Status::Error("the iteration limit was reached before the whole prescribed move "
                             "was applied");
      u = std::move(trial);
      reached = to;
      report.stoppedAtLimit = true;
      break;
    }
    if (f == Failure::None) {
      u = std::move(trial);
      reached = to;
      ++report.substeps;
      // Back up towards whole steps (as Newton's load steps do): a halving was for one hard
      // stretch of the move, not for the rest of it.
      if (halvings > 0) {
        --halvings;
        step *= 2.0;
      }
      continue;
    }
    pb.prescribed = contact;
    ++report.rejectedSubsteps;
    // The step never gets smaller than 2^-maxSubstepHalvings of the move: past that point a
    // cell inverts whatever the step (the move's limit for this mesh), and halving on would
    // creep towards it without end.
    if (f == Failure::Fallback || ++halvings > sys.options.maxSubstepHalvings) {
      why = solver.why.empty() ? "a cell would invert at the smallest sub-step" : solver.why;
      break;
    }
    step *= 0.5;
  }

  if (reached < 1.0) {
    if (!sys.options.fallBackToNewton)
      return Status::Error("the precomputed large-deformation solve did not converge: " + why);
    report.fellBack = true;
    report.fallbackReason = why;
    LargeDeformationOptions newton = sys.options.newton;
    newton.slidingLiftOff = sys.options.slidingLiftOff;
    newton.tolerance = sys.options.tolerance;
    status = SolveLargeDeformation(request, input, newton, result, report.newton);
    if (!status)
      return status;
    report.smallestVolumeRatio = report.newton.smallestVolumeRatio;
    report.largestGreenStrain = report.newton.largestGreenStrain;
    report.largestStrainCell = report.newton.largestStrainCell;
    report.liftedNodes = report.newton.liftedNodes;
    return status;
  }

  if (sys.backend && report.deviceNote.empty())
    report.device = sys.backend->name();
  result.backend = report.device;
  StageClock finish;
  FinalState finalState;
  // The measures read every cell: on the backend where it has the cells.
  DeformationMeasures onDevice;
  bool measured = false;
  if (sys.forces) {
    const Status s = sys.forces->measure(u, onDevice.smallestVolumeRatio,
                                         onDevice.largestGreenStrain, onDevice.largestStrainCell);
    measured = s.ok;
    // The backend numbers the cells as the structure does.
    onDevice.largestStrainCell = st.requestCell(onDevice.largestStrainCell);
  }
  status = FinishSolve(request, input, pb, u, solver.lastResidual(), result, finalState,
                       measured ? &onDevice : nullptr);
  report.smallestVolumeRatio = finalState.measures.smallestVolumeRatio;
  report.largestGreenStrain = finalState.measures.largestGreenStrain;
  report.largestStrainCell = finalState.measures.largestStrainCell;
  report.liftedNodes = finalState.liftedNodes;
  report.finishMs = finish.elapsedMs();
  if (!status)
    return status;
  if (report.stoppedAtLimit) {
    result.timings[Stage::Total].ms = total.elapsedMs();
    return Status::Ok(); // not a converged state: nothing to refactor at or to start from
  }
  // A drag: a warm solve of the same loads whose prescribed change is no larger than the move
  // itself. Its next edit is most likely the same change again, so the tangent is factored there,
  // one step ahead, where the next solve's iterates will be (any positive definite factor serves
  // as the initial Hessian; this one is the nearest to the next solve's).
  const Eigen::VectorXd& target = pb.target; // the whole move's (reached is 1)
  const Eigen::Index n = u.size();
  bool drag = false, steady = false;
  if (report.warmStarted) {
    // In one pass: whether the loads are the same, the change's size against the move's, and
    // whether the change repeats the one before (a steady drag; without a state before it the
    // comparison reads the last targets twice and is not used). A pass apart from the warm-start
    // test's, which reads fewer vectors: one pass over all of them ran slower than the two.
    const bool twoBefore = sys.options.factorAheadOrder >= 2 && warm->before.size() == n &&
                           warm->targetBefore.size() == n;
    const double* last = warm->target.data();
    const double* lastButOne = twoBefore ? warm->targetBefore.data() : last;
    bool sameLoad = true;
    double change2 = 0.0, target2 = 0.0, repeat2 = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      sameLoad = sameLoad && pb.externalLoad[i] == warm->load[i];
      const double c = target[i] - last[i], r = last[i] - lastButOne[i] - c;
      change2 += c * c;
      target2 += target[i] * target[i];
      repeat2 += r * r;
    }
    drag = sameLoad && change2 <= target2;
    steady = twoBefore && repeat2 <= kSteadyDrag * kSteadyDrag * change2;
  }
  if (sys.options.backgroundRefactorization) {
    if (drag && sys.options.factorAhead) {
      // Where the same change again leads. After two equal changes (a steady drag) the parabola
      // through the last three states: its error is third order in the step where the line's is
      // second, and the next predictor's Newton step from there lands that much nearer.
      auto extrapolate = [steady, n](const Eigen::VectorXd& now, const Eigen::VectorXd& before,
                                     const Eigen::VectorXd& twoBefore) {
        Eigen::VectorXd out(n);
        if (steady)
          for (Eigen::Index i = 0; i < n; ++i)
            out[i] = 3.0 * (now[i] - before[i]) + twoBefore[i];
        else
          for (Eigen::Index i = 0; i < n; ++i)
            out[i] = 2.0 * now[i] - before[i];
        return out;
      };
      Eigen::VectorXd ahead = extrapolate(u, warm->u, warm->before);
      const bool contactAhead = !st.liftOffDofs.empty() && sys.options.predictContactAhead;
      Problem aheadValues;
      if (contactAhead || sys.options.aheadCorrections > 0) {
        aheadValues.st = pb.st;
        aheadValues.target = extrapolate(target, warm->target, warm->targetBefore);
        aheadValues.externalLoad = pb.externalLoad;
        aheadValues.linearForce = pb.linearForce;
      }
      sys.requestRefactorization(u, pb.prescribed, std::move(ahead), std::move(aheadValues),
                                 contactAhead);
    } else {
      sys.requestRefactorization(u, pb.prescribed);
    }
  }
  if (converged) {
    converged->system = &sys;
    converged->u = std::move(u);
    converged->prescribed = pb.prescribed;
    converged->target = std::move(pb.target);
    converged->load = std::move(pb.externalLoad);
    converged->force = solver.takeLastForce();
    if (drag) {
      converged->before = warm->u;
      converged->targetBefore = warm->target;
    }
  }
  result.timings[Stage::Total].ms = total.elapsedMs();
  return Status::Ok();
}

} // namespace

Status PrecomputeLargeDeformation(const PrecomputeRequest& request,
                                  const PrecomputedLargeDeformationOptions& options,
                                  std::shared_ptr<LargeDeformationSystem>& system) {
  return ReturnStatusOnException("the large-deformation precompute", [&]() -> Status {
    return PrecomputeImpl(request, options, system);
  });
}

Status SolvePrecomputedLargeDeformation(LargeDeformationSystem& system, const SolveInput& input,
                                        const LargeDeformationState* warm, SolveResult& result,
                                        PrecomputedLargeDeformationReport& report,
                                        LargeDeformationState* converged, int iterationLimit) {
  return ReturnStatusOnException("the large-deformation solve", [&]() -> Status {
    return SolveImpl(system, input, warm, result, report, converged, iterationLimit);
  });
}

void WaitForRefactorization(LargeDeformationSystem& system) {
  system.waitIdle();
}

void StopRefactorization(LargeDeformationSystem& system) {
  system.stopWorker();
}

StageTimings PrecomputeTimings(const LargeDeformationSystem& system) {
  return system.timings;
}

std::string DescribeFactorOnDevice(const LargeDeformationSystem& system) {
  const std::shared_ptr<const TangentFactor> factor = system.factor();
  if (!system.backend)
    return "no backend";
  if (!factor || !factor->device)
    return factor ? factor->deviceError : "no factor";
  return factor->device->describe();
}

int BackgroundRefactorizations(const LargeDeformationSystem& system) {
  return system.backgroundCount();
}

int FactorsAheadCorrected(const LargeDeformationSystem& system) {
  return system.correctedCount();
}

int FactorsAheadRefused(const LargeDeformationSystem& system) {
  return system.aheadFailures();
}

} // namespace faceplan
