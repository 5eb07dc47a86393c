// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// RAII wrapper of a CHOLMOD supernodal Cholesky factor of a symmetric positive definite matrix
// given by its upper triangle. Solves are serialized (a cholmod_common is not thread-safe).
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"
#include "SparseSolver/FillReducingOrdering.h"

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

struct cholmod_factor_struct;
struct cholmod_common_struct;

namespace faceplan {

// How far the symbolic analysis merges columns into relaxed supernodes. CHOLMOD's own settings suit
// the CPU factorization (multifrontal, MultifrontalCholesky.h) and the response's substitutions;
// coarser supernodes (fewer, larger blocks, more explicit zeros) suit the GPU, whose factorization
// and sweeps pay a fixed cost per supernode.
enum class SupernodeRelaxation { Cholmod, Coarse };

class CholmodFactor {
public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  // For the next analyze() (CHOLMOD's settings until set).
  void setSupernodeRelaxation(SupernodeRelaxation relaxation);

  // Fill-reducing ordering and symbolic factorization (the "reordering" stage): CHOLMOD's own
  // choice, or the given ordering (see FillReducingOrdering.h), whose trailing DOFs then allow
  // solveTrailing().
  Status analyze(const SparseMatrix& upper, const FillReducingOrdering* ordering = nullptr);
  // The same with several candidate orderings: each is analysed symbolically and the one with the
  // lowest cost(factor non-zeros, factorization flops, DOFs kept in the trailing block) is kept.
  using OrderingCost = std::function<double(double nonzeros, double flops, int trailingDofs)>;
  Status analyze(const SparseMatrix& upper, const std::vector<FillReducingOrdering>& candidates,
                 const OrderingCost& cost);
  // The analysis `analysed` made (its ordering and symbolic factor, copied): for a matrix with the
  // same pattern, factored again and again (the large-deformation tangent), without the symbolic
  // analysis each time. `analysed` may be used by other threads meanwhile (it is only read).
  Status analyzeLike(const CholmodFactor& analysed);
  // Numeric factorization; fails with a message if the matrix is not positive definite.
  Status factorize(const SparseMatrix& upper);
  // x = A^-1 b for one or many columns.
  Status solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;
  // The same with a private CHOLMOD workspace, so several threads may solve at once (the factor
  // is only read). Used for the many right-hand sides of the dense response.
  Status solveConcurrently(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;

  // x = A^-1 b for sparse right-hand sides that are non-zero only on the trailing DOFs of the
  // ordering given to analyze(): the forward substitution is a dense triangular solve with the
  // factor's trailing block, so this costs about half of solve(). Safe to call from several threads
  // at once (private CHOLMOD workspace). Fails if b has a non-zero elsewhere or trailingDofs() is
  // 0.
  Status solveTrailing(const SparseMatrix& b, Eigen::MatrixXd& x) const;
  // DOFs in the factor's trailing block (0 when analyze() had no ordering or the symbolic analysis
  // did not keep them last).
  int trailingDofs() const;

  // Row p of a solution in elimination order holds DOF d where eliminationPosition()[d] == p.
  const std::vector<int>& eliminationPosition() const; // valid after analyze()
  // Read-only views for solvers outside this class (PrunedBackSubstitution): the numeric factor
  // (null unless factorized) and its trailing diagonal block as a dense lower triangle.
  const cholmod_factor_struct* numericFactor() const;
  // The analysis (symbolic, or numeric once factorized; null before analyze()): its supernodal
  // structure and ordering, for a factorization elsewhere (SinglePrecisionFactor::factorize). Read
  // only; the structure does not change until the next analyze() or analyzeLike().
  const cholmod_factor_struct* analysis() const;
  const Eigen::MatrixXd& trailingFactorBlock() const;
  // Rows of a matrix in elimination order put back in the original DOF order.
  Eigen::MatrixXd fromEliminationOrder(const Eigen::Ref<const Eigen::MatrixXd>& permuted) const;

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
  // Bytes the numeric factor will hold, known after analyze() (before factorize() allocates it):
  // CHOLMOD's value and index arrays plus the trailing block's dense copy.
  double factorBytes() const;
  double factorFlops() const; // of the numeric factorization, from the last analyze()
  // CHOLMOD's cheap reciprocal condition estimate, (min diag L / max diag L)^2.
  double reciprocalConditionEstimate() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace faceplan
