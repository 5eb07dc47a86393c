#include "CholmodFactor.h"

#include "CholmodViews.h"

#include "BlasThreads.h"

#include <algorithm>
#include <cholmod.h>
#include <string>
#include <thread>

namespace faceplan {

struct CholmodFactor::Impl {
  mutable cholmod_common common;
  cholmod_factor* factor = nullptr;
  bool numeric = false; // factor holds numeric values (factorize or markFactorized)
  mutable std::mutex mutex;
  // Solve workspaces reused across solves, so a per-edit solve allocates nothing.
  mutable cholmod_dense* x = nullptr;
  mutable cholmod_dense* y = nullptr;
  mutable cholmod_dense* e = nullptr;

  Impl() {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.print = 0;
    common.error_handler = nullptr;
  }
  ~Impl() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
};

namespace {

void CopyOut(const cholmod_dense* solution, Eigen::Index rows, Eigen::Index cols, Eigen::MatrixXd& x) {
  x.resize(rows, cols);
  const double* src = static_cast<const double*>(solution->x);
  for (Eigen::Index c = 0; c < cols; ++c)
    std::copy(src + c * solution->d, src + c * solution->d + rows, x.col(c).data());
}

} // namespace

CholmodFactor::CholmodFactor() : impl_(std::make_unique<Impl>()) {}
CholmodFactor::~CholmodFactor() = default;

Status CholmodFactor::analyze(const SparseMatrix& upper) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!upper.isCompressed()) return Status::Error("internal: matrix not compressed");
  cholmod_sparse view = ViewUpper(upper);
  cholmod_free_factor(&impl_->factor, &impl_->common);
  impl_->numeric = false;
  impl_->factor = cholmod_analyze(&view, &impl_->common);
  if (!impl_->factor || impl_->common.status < CHOLMOD_OK)
    return Status::Error("CHOLMOD ordering failed (status " + std::to_string(impl_->common.status) +
                         "; out of memory?)");
  return Status::Ok();
}

Status CholmodFactor::factorize(const SparseMatrix& upper) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->factor) return Status::Error("internal: factorize before analyze");
  cholmod_sparse view = ViewUpper(upper);
  impl_->numeric = false;
  // At most 8 OpenBLAS threads for the supernodal BLAS calls: on the 16-core GPU machine OpenBLAS
  // with all 16 threads made this factorization 20x slower than with 8 (BENCHMARKS.md, GPU section:
  // 14.1 s against 0.72 s at 100k tetrahedra, 127 s against 21.6 s at 1M), and fewer threads lose
  // little elsewhere. A no-op when the BLAS is not OpenBLAS.
  const int blasThreads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
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
  return Status::Ok();
}

Status CholmodFactor::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->factor || !impl_->numeric) return Status::Error("internal: solve before factorize");
  if (static_cast<size_t>(b.rows()) != impl_->factor->n)
    return Status::Error("internal: right-hand side has the wrong size");
  cholmod_dense rhs = ViewDense(b);
  const int ok = cholmod_solve2(CHOLMOD_A, impl_->factor, &rhs, nullptr, &impl_->x, nullptr,
                                &impl_->y, &impl_->e, &impl_->common);
  if (!ok || !impl_->x) return Status::Error("CHOLMOD solve failed (out of memory?)");
  CopyOut(impl_->x, b.rows(), b.cols(), x);
  return Status::Ok();
}

Status CholmodFactor::solveConcurrently(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  if (!impl_->factor || !impl_->numeric) return Status::Error("internal: solve before factorize");
  if (static_cast<size_t>(b.rows()) != impl_->factor->n)
    return Status::Error("internal: right-hand side has the wrong size");
  cholmod_common common;
  cholmod_start(&common);
  common.print = 0;
  common.error_handler = nullptr;
  cholmod_dense rhs = ViewDense(b);
  cholmod_dense* solution = cholmod_solve(CHOLMOD_A, impl_->factor, &rhs, &common);
  Status status = Status::Ok();
  if (!solution) status = Status::Error("CHOLMOD solve failed (out of memory?)");
  else CopyOut(solution, b.rows(), b.cols(), x);
  cholmod_free_dense(&solution, &common);
  cholmod_finish(&common);
  return status;
}

bool CholmodFactor::isFactorized() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->factor && impl_->numeric;
}

cholmod_factor* CholmodFactor::cholmodFactor() { return impl_->factor; }
cholmod_common* CholmodFactor::cholmodCommon() { return &impl_->common; }

Status CholmodFactor::markFactorized() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  const cholmod_factor* L = impl_->factor;
  if (!L) return Status::Error("internal: markFactorized before analyze");
  if (L->xtype != CHOLMOD_REAL || !L->x || !L->is_ll || L->minor < L->n)
    return Status::Error("internal: markFactorized on a factor without numeric LL^T values");
  impl_->numeric = true;
  return Status::Ok();
}

double CholmodFactor::factorNonzeros() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->common.lnz;
}

double CholmodFactor::reciprocalConditionEstimate() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->factor && impl_->numeric ? cholmod_rcond(impl_->factor, &impl_->common) : 0.0;
}

} // namespace faceplan
