#pragma once
// RAII wrapper of a CHOLMOD supernodal Cholesky factor of a symmetric positive definite matrix
// given by its upper triangle. Solves are serialized (a cholmod_common is not thread-safe).
#include "Status.h"
#include "StiffnessAssembly.h"

#include <Eigen/Core>
#include <memory>
#include <mutex>

struct cholmod_factor_struct;
struct cholmod_common_struct;

namespace faceplan {

class CholmodFactor {
public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  // Fill-reducing ordering and symbolic factorization (the "reordering" stage).
  Status analyze(const SparseMatrix& upper);
  // Numeric factorization; fails with a message if the matrix is not positive definite.
  Status factorize(const SparseMatrix& upper);
  // x = A^-1 b for one or many columns.
  Status solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;
  // The same with a private CHOLMOD workspace, so several threads may solve at once (the factor
  // is only read). Used for the many right-hand sides of the dense response.
  Status solveConcurrently(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;

  // True after a successful factorize() or markFactorized(); analyze() resets it.
  bool isFactorized() const;

  // For a backend that computes the numeric factorization itself (Cuda/, through
  // ComputeBackend::factorAndBuildResponse): the CHOLMOD factor after analyze() (supernodal, 32-bit
  // indices; symbolic until factorized) and the cholmod_common it belongs to, for CHOLMOD calls on
  // it such as cholmod_change_factor. Null before analyze(). Not for use concurrently with solves.
  cholmod_factor_struct* cholmodFactor();
  cholmod_common_struct* cholmodCommon();
  // The caller has written a numeric LL^T factor of the analysed matrix into cholmodFactor()
  // (CHOLMOD's own supernodal layout): solves may use it. Fails if the factor is not numeric.
  Status markFactorized();

  double factorNonzeros() const;
  // CHOLMOD's cheap reciprocal condition estimate, (min diag L / max diag L)^2.
  double reciprocalConditionEstimate() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace faceplan
