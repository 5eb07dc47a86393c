// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Preconditioned conjugate gradients on the free system K_FF u_F = f_F - K_FR u_R, in double or
// single precision, with a Jacobi or an incomplete Cholesky preconditioner (Eigen). The setup
// (matrix copy, preconditioner) is the precompute; each solve takes its own relative tolerance
// ||K x - b|| / ||b|| and an optional starting guess (warm start). Never throws.
#include "Comparison/FreeSystem.h"

#include <memory>

namespace faceplan {

enum class CGPreconditioner { Jacobi, IncompleteCholesky };
enum class CGPrecision { Double, Single };
const char* CGPreconditionerName(CGPreconditioner p);

struct CGOptions {
  CGPreconditioner preconditioner = CGPreconditioner::IncompleteCholesky;
  CGPrecision precision = CGPrecision::Double;
  int maxIterations = 0; // 0: 2 x the number of unknowns (Eigen's default)
};

struct CGReport {
  int iterations = 0;
  bool converged = false;         // Eigen reached the tolerance within maxIterations
  double estimatedResidual = 0.0; // Eigen's own relative residual (in the working precision)
  double relativeResidual = 0.0;  // ||K_FF x - b|| / ||b||, recomputed in double
  double solveMs = 0.0;
};

class ConjugateGradientSolver {
public:
  ConjugateGradientSolver();
  ~ConjugateGradientSolver();
  ConjugateGradientSolver(const ConjugateGradientSolver&) = delete;
  ConjugateGradientSolver& operator=(const ConjugateGradientSolver&) = delete;

  // Keeps a reference to system.kff (which must outlive the solver) and builds the preconditioner.
  Status setup(const FreeSystem& system, const CGOptions& options);
  double setupMs() const;

  // x = K_FF^-1 b to `tolerance` (relative residual). `guess` (may be null) starts the iteration.
  Status solve(const Eigen::VectorXd& b, double tolerance, const Eigen::VectorXd* guess,
               Eigen::VectorXd& x, CGReport& report) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace faceplan
