// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A single-precision copy of a numeric supernodal LL^T factor (CholmodFactor), for substitutions
// that need only be close to exact: an initial inverse Hessian or a preconditioner, whose caller
// measures convergence with the double-precision residual. A substitution reads every non-zero of
// the factor twice and is bound by memory bandwidth, so half the bytes is about half the time (and
// a factor of a few million non-zeros then fits a server's last-level cache).
//
// The substitutions run on two threads where the supernodal tree splits into two subtrees of
// similar work below a small top part: each subtree's forward sweep accumulates its updates of the
// top part privately, the top part runs alone, then the subtrees' backward sweeps run side by side.
#include "Common/Status.h"

#include <Eigen/Core>
#include <memory>

namespace faceplan {

class CholmodFactor;

class SinglePrecisionFactor {
public:
  SinglePrecisionFactor();
  ~SinglePrecisionFactor();
  SinglePrecisionFactor(const SinglePrecisionFactor&) = delete;
  SinglePrecisionFactor& operator=(const SinglePrecisionFactor&) = delete;

  // Copies factor's numeric supernodal LL^T factor (fails for any other kind). threads: 1 or 2.
  Status assign(const CholmodFactor& factor, int threads = 2);
  // x = (L L^T)^-1 b (the factored matrix's inverse applied to b, original numbering), in single
  // precision after scaling b to unit largest entry. Safe to call from several threads at once.
  Status solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  Eigen::Index rows() const;
  // Bytes of the single-precision values.
  double valueBytes() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace faceplan
