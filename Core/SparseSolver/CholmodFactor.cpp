// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/CholmodFactor.h"
#include "Common/InversePermutation.h"
#include "Common/ParallelFor.h"
#include "Common/WorkerThreads.h"

#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/MultifrontalCholesky.h"
#include "SparseSolver/SymbolicAnalysis.h"

#include "Common/BlasThreads.h"

#include <algorithm>
#include <cholmod.h>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace faceplan {

struct CholmodFactor::Impl {
  QuietCholmodCommon quiet;
  cholmod_common& common = quiet.common;
  cholmod_factor* factor = nullptr;
  bool numeric = false; // factor holds numeric values (factorize or markFactorized)
  mutable std::mutex mutex;
  // Solve workspaces reused across solves, so a per-edit solve allocates nothing.
  mutable cholmod_dense* x = nullptr;
  mutable cholmod_dense* y = nullptr;
  mutable cholmod_dense* e = nullptr;
  // solveTrailing(): trailing block size, each DOF's position in the elimination order, and the
  // factor's trailing diagonal block as a dense lower triangle (filled once the factor is numeric).
  int trailing = 0;
  std::vector<int> position;
  Eigen::MatrixXd trailingBlock;

  void extractTrailingBlock();

  Impl() {
    common.supernodal = CHOLMOD_SUPERNODAL;
    ApplySupernodeRelaxation(common, SupernodeRelaxation::Cholmod);
  }
  ~Impl() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_free_factor(&factor, &common);
  }
};

void CholmodFactor::Impl::extractTrailingBlock() {
  trailingBlock.resize(0, 0);
  if (trailing == 0 || !factor || !factor->is_super)
    return;
  const int n = static_cast<int>(factor->n), first = n - trailing;
  trailingBlock.resize(trailing, trailing);
  const int* super = static_cast<const int*>(factor->super);
  const int* pi = static_cast<const int*>(factor->pi);
  const int* px = static_cast<const int*>(factor->px);
  const int* s = static_cast<const int*>(factor->s);
  const double* values = static_cast<const double*>(factor->x);
  std::vector<int> supernodeOf(trailing);
  for (size_t k = 0; k < factor->nsuper; ++k)
    for (int j = std::max(super[k], first); j < super[k + 1]; ++j)
      supernodeOf[j - first] = static_cast<int>(k);
  // Column by column on every core: on large meshes the block has thousands of columns and runs
  // beside the GPU response's download.
  ParallelFor(trailing, 64, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      const int j = first + static_cast<int>(c), k = supernodeOf[c];
      const int rows = pi[k + 1] - pi[k];
      double* column = trailingBlock.col(c).data();
      std::fill(column, column + trailing, 0.0); // zero where the pattern has no entry
      for (int r = 0; r < rows; ++r) {
        const int row = s[pi[k] + r];
        if (row >= j)
          column[row - first] = values[px[k] + size_t(j - super[k]) * rows + r];
      }
    }
  });
}

namespace {

void CopyOut(const cholmod_dense* solution, Eigen::Index rows, Eigen::Index cols,
             Eigen::MatrixXd& x) {
  x.resize(rows, cols);
  const double* src = static_cast<const double*>(solution->x);
  for (Eigen::Index c = 0; c < cols; ++c)
    std::copy(src + c * solution->d, src + c * solution->d + rows, x.col(c).data());
}

bool CholmodFactorizationForced() {
  const char* choice = std::getenv("FACEPLAN_FACTORIZATION");
  return choice && std::strcmp(choice, "cholmod") == 0;
}

} // namespace

CholmodFactor::CholmodFactor() : impl_(std::make_unique<Impl>()) {}
CholmodFactor::~CholmodFactor() = default;

void CholmodFactor::setSupernodeRelaxation(SupernodeRelaxation relaxation) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  ApplySupernodeRelaxation(impl_->common, relaxation);
}

Status CholmodFactor::analyze(const SparseMatrix& upper, const FillReducingOrdering* ordering) {
  if (!ordering)
    return analyze(upper, std::vector<FillReducingOrdering>{}, {});
  return analyze(upper, std::vector<FillReducingOrdering>{*ordering}, {});
}

Status CholmodFactor::analyze(const SparseMatrix& upper,
                              const std::vector<FillReducingOrdering>& candidates,
                              const OrderingCost& cost) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!upper.isCompressed())
    return Status::Error("internal: matrix not compressed");
  const int n = static_cast<int>(upper.rows());
  for (const FillReducingOrdering& c : candidates)
    if (static_cast<int>(c.permutation.size()) != n)
      return Status::Error("internal: ordering does not match the matrix");
  cholmod_sparse view = ViewUpper(upper);
  cholmod_common& common = impl_->common;
  cholmod_free_factor(&impl_->factor, &common);
  impl_->numeric = false;
  impl_->trailing = 0;
  impl_->trailingBlock.resize(0, 0);

  // Where the DOFs a candidate put last ended up: its trailing size if they fill the last
  // positions of the analysed factor (CHOLMOD's etree postorder keeps a trailing clique last).
  auto keptTrailing = [n](const cholmod_factor* L, const FillReducingOrdering& c,
                          std::vector<int>& position) {
    const int* perm = static_cast<const int*>(L->Perm);
    position = InversePermutation(perm, n);
    if (c.trailingDofs == 0 || !L->is_super)
      return 0;
    int first = n;
    for (int k = n - c.trailingDofs; k < n; ++k)
      first = std::min(first, position[c.permutation[k]]);
    return first == n - c.trailingDofs ? c.trailingDofs : 0;
  };

  if (!candidates.empty()) {
    // Only the given ordering, then CHOLMOD's postorder; the cheapest candidate by `cost`.
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_GIVEN;
    common.postorder = 1;
    double bestCost = 0.0, bestLnz = 0.0, bestFlops = 0.0;
    for (const FillReducingOrdering& c : candidates) {
      cholmod_factor* L = AnalyzeInGivenOrder(upper, c.permutation, common);
      if (!L)
        continue;
      std::vector<int> position;
      const int trailing = keptTrailing(L, c, position);
      const double score = cost ? cost(common.lnz, common.fl, trailing) : 0.0;
      if (!impl_->factor || score < bestCost) {
        cholmod_free_factor(&impl_->factor, &common);
        impl_->factor = L;
        impl_->trailing = trailing;
        impl_->position.swap(position);
        bestCost = score;
        bestLnz = common.lnz;
        bestFlops = common.fl;
      } else {
        cholmod_free_factor(&L, &common);
      }
    }
    common.lnz = bestLnz; // factorNonzeros() and factorFlops() report the kept candidate
    common.fl = bestFlops;
    common.nmethods = 0; // back to CHOLMOD's default choice for later analyses
  }
  const bool ownChoice = !impl_->factor;
  if (ownChoice) { // no candidate, or none could be analysed: CHOLMOD's own ordering
    common.status = CHOLMOD_OK;
    std::lock_guard<std::mutex> metis(MetisMutex()); // CHOLMOD may try METIS
    impl_->factor = cholmod_analyze(&view, &common);
  }
  if (!impl_->factor || common.status < CHOLMOD_OK)
    return Status::Error("CHOLMOD ordering failed (status " + std::to_string(common.status) +
                         "; out of memory?)");
  if (ownChoice)
    keptTrailing(impl_->factor, FillReducingOrdering{}, impl_->position);
  return Status::Ok();
}

Status CholmodFactor::analyzeLike(const CholmodFactor& analysed) {
  if (&analysed == this)
    return Status::Error("internal: a factor cannot copy its own analysis");
  std::scoped_lock locks(impl_->mutex, analysed.impl_->mutex);
  if (!analysed.impl_->factor)
    return Status::Error("internal: the analysis to copy has not been made");
  cholmod_common& common = impl_->common;
  cholmod_free_factor(&impl_->factor, &common);
  impl_->numeric = false;
  impl_->trailingBlock.resize(0, 0);
  impl_->factor = cholmod_copy_factor(analysed.impl_->factor, &common);
  if (!impl_->factor)
    return Status::Error("CHOLMOD could not copy the analysis (out of memory?)");
  impl_->trailing = analysed.impl_->trailing;
  impl_->position = analysed.impl_->position;
  return Status::Ok();
}

Status CholmodFactor::factorize(const SparseMatrix& upper) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->factor)
    return Status::Error("internal: factorize before analyze");
  cholmod_sparse view = ViewUpper(upper);
  impl_->numeric = false;
  // Supernodal analyses are factored multifrontally, subtrees on their own threads
  // (MultifrontalCholesky.h). Where that fails (not positive definite, out of memory) CHOLMOD
  // factors again, so the message is CHOLMOD's as before (the first failing column).
  // FACEPLAN_FACTORIZATION=cholmod keeps CHOLMOD's own (for comparisons).
  if (impl_->factor->is_super && impl_->factor->itype == CHOLMOD_INT &&
      !CholmodFactorizationForced()) {
    Status s = MultifrontalFactorize(upper, impl_->factor, &impl_->common, WorkerThreads(16));
    if (s) {
      impl_->numeric = true;
      impl_->extractTrailingBlock();
      return Status::Ok();
    }
  }
  // At most 8 OpenBLAS threads for the supernodal BLAS calls: with 16, OpenBLAS made this
  // factorization many times slower than with 8 (BENCHMARKS.md, "GPU: the CUDA backend"), and
  // fewer threads lose little elsewhere. A no-op when the BLAS is not OpenBLAS.
  const int blasThreads = WorkerThreads(8);
  ScopedBlasThreads cappedBlas(blasThreads);
  const int ok = cholmod_factorize(&view, impl_->factor, &impl_->common);
  if (!ok || impl_->common.status == CHOLMOD_OUT_OF_MEMORY)
    return Status::Error("CHOLMOD factorization ran out of memory");
  if (impl_->common.status == CHOLMOD_NOT_POSDEF || impl_->factor->minor < impl_->factor->n)
    return Status::Error("stiffness matrix is not positive definite (CHOLMOD stopped at column " +
                         std::to_string(impl_->factor->minor) +
                         "): a part of the mesh is not held by any constrained node, or an "
                         "element is degenerate");
  impl_->numeric = true;
  impl_->extractTrailingBlock();
  return Status::Ok();
}

Status CholmodFactor::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->factor || !impl_->numeric)
    return Status::Error("internal: solve before factorize");
  if (static_cast<size_t>(b.rows()) != impl_->factor->n)
    return Status::Error("internal: right-hand side has the wrong size");
  cholmod_dense rhs = ViewDense(b);
  // A pinned BLAS thread count (the factorization's cap): a solve's round-off must not depend on
  // the count another thread's precompute set meanwhile (OpenBLAS splits some products by it).
  ScopedBlasThreads pinnedBlas(WorkerThreads(8), BlasScope::Pinned);
  const int ok = cholmod_solve2(CHOLMOD_A, impl_->factor, &rhs, nullptr, &impl_->x, nullptr,
                                &impl_->y, &impl_->e, &impl_->common);
  if (!ok || !impl_->x)
    return Status::Error("CHOLMOD solve failed (out of memory?)");
  CopyOut(impl_->x, b.rows(), b.cols(), x);
  return Status::Ok();
}

Status CholmodFactor::solveConcurrently(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  if (!impl_->factor || !impl_->numeric)
    return Status::Error("internal: solve before factorize");
  if (static_cast<size_t>(b.rows()) != impl_->factor->n)
    return Status::Error("internal: right-hand side has the wrong size");
  QuietCholmodCommon local;
  cholmod_dense rhs = ViewDense(b);
  cholmod_dense* solution = cholmod_solve(CHOLMOD_A, impl_->factor, &rhs, &local.common);
  Status status = Status::Ok();
  if (!solution)
    status = Status::Error("CHOLMOD solve failed (out of memory?)");
  else
    CopyOut(solution, b.rows(), b.cols(), x);
  cholmod_free_dense(&solution, &local.common);
  return status;
}

const std::vector<int>& CholmodFactor::eliminationPosition() const {
  return impl_->position;
}

const cholmod_factor* CholmodFactor::numericFactor() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->numeric ? impl_->factor : nullptr;
}

const cholmod_factor* CholmodFactor::analysis() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->factor;
}

const Eigen::MatrixXd& CholmodFactor::trailingFactorBlock() const {
  return impl_->trailingBlock;
}

Eigen::MatrixXd
CholmodFactor::fromEliminationOrder(const Eigen::Ref<const Eigen::MatrixXd>& permuted) const {
  const std::vector<int>& position = impl_->position;
  Eigen::MatrixXd original(permuted.rows(), permuted.cols());
  for (Eigen::Index dof = 0; dof < original.rows(); ++dof)
    original.row(dof) = permuted.row(position[dof]);
  return original;
}

Status CholmodFactor::solveTrailing(const SparseMatrix& b, Eigen::MatrixXd& x) const {
  const cholmod_factor* L = impl_->factor;
  if (!L || !impl_->numeric)
    return Status::Error("internal: solve before factorize");
  const int n = static_cast<int>(L->n), t = impl_->trailing, first = n - t;
  if (t == 0 || impl_->trailingBlock.rows() != t)
    return Status::Error("internal: no trailing block");
  if (b.rows() != n)
    return Status::Error("internal: right-hand side has the wrong size");
  const Eigen::Index m = b.cols();
  // Forward: L^-1 P b is zero above the trailing block, which is a dense triangular solve.
  Eigen::MatrixXd forward = Eigen::MatrixXd::Zero(n, m);
  auto tail = forward.bottomRows(t);
  for (Eigen::Index c = 0; c < m; ++c)
    for (SparseMatrix::InnerIterator it(b, c); it; ++it) {
      const int p = impl_->position[it.row()];
      if (p < first)
        return Status::Error("internal: right-hand side outside the trailing DOFs");
      tail(p - first, c) = it.value();
    }
  impl_->trailingBlock.triangularView<Eigen::Lower>().solveInPlace(tail);
  // Backward over the whole factor, with a private CHOLMOD workspace (callers may be concurrent).
  QuietCholmodCommon local;
  cholmod_dense rhs = ViewDense(forward);
  cholmod_dense *solution = nullptr, *y = nullptr, *e = nullptr;
  ScopedBlasThreads pinnedBlas(WorkerThreads(8), BlasScope::Pinned); // as in solve()
  const int ok = cholmod_solve2(CHOLMOD_Lt, const_cast<cholmod_factor*>(L), &rhs, nullptr,
                                &solution, nullptr, &y, &e, &local.common);
  Status status = Status::Ok();
  if (!ok || !solution)
    status = Status::Error("CHOLMOD solve failed (out of memory?)");
  else
    x = fromEliminationOrder(
        Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(solution->x), n, m));
  cholmod_free_dense(&solution, &local.common);
  cholmod_free_dense(&y, &local.common);
  cholmod_free_dense(&e, &local.common);
  return status;
}

int CholmodFactor::trailingDofs() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->trailing;
}

bool CholmodFactor::isFactorized() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->factor && impl_->numeric;
}

cholmod_factor* CholmodFactor::cholmodFactor() {
  return impl_->factor;
}
cholmod_common* CholmodFactor::cholmodCommon() {
  return &impl_->common;
}

Status CholmodFactor::markFactorized() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  const cholmod_factor* L = impl_->factor;
  if (!L)
    return Status::Error("internal: markFactorized before analyze");
  if (L->xtype != CHOLMOD_REAL || !L->x || !L->is_ll || L->minor < L->n)
    return Status::Error("internal: markFactorized on a factor without numeric LL^T values");
  impl_->numeric = true;
  impl_->extractTrailingBlock();
  return Status::Ok();
}

double CholmodFactor::factorNonzeros() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->common.lnz;
}

double CholmodFactor::factorBytes() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  const cholmod_factor* L = impl_->factor;
  if (!L)
    return 0.0;
  const double trailing = double(impl_->trailing);
  const double sparse = L->is_super ? 8.0 * double(L->xsize) + sizeof(int) * double(L->ssize)
                                    : (8.0 + sizeof(int)) * impl_->common.lnz;
  return sparse + 8.0 * trailing * trailing;
}

double CholmodFactor::factorFlops() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->common.fl;
}

double CholmodFactor::reciprocalConditionEstimate() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->factor && impl_->numeric ? cholmod_rcond(impl_->factor, &impl_->common) : 0.0;
}

} // namespace faceplan
