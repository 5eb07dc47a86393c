// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Sparse Cholesky of K_FF in single precision (Eigen::SimplicialLLT<float>, AMD ordering), with
// optional iterative refinement in double (residuals with the double K_FF): zero steps is the
// plain float solve, whose error is what single precision costs; one or two steps recover double
// accuracy on well-conditioned systems. Never throws.
#include "Comparison/FreeSystem.h"

#include <memory>

namespace faceplan {

struct SinglePrecisionReport {
  double relativeResidual = 0.0; // ||K_FF x - b|| / ||b|| in double
  double solveMs = 0.0;
};

class SinglePrecisionCholesky {
public:
  SinglePrecisionCholesky();
  ~SinglePrecisionCholesky();
  SinglePrecisionCholesky(const SinglePrecisionCholesky&) = delete;
  SinglePrecisionCholesky& operator=(const SinglePrecisionCholesky&) = delete;

  // Keeps a reference to system (must outlive this) and factors K_FF cast to float.
  Status factorize(const FreeSystem& system);
  double factorizeMs() const;

  Status solve(const Eigen::VectorXd& b, int refinementSteps, Eigen::VectorXd& x,
               SinglePrecisionReport& report) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace faceplan
