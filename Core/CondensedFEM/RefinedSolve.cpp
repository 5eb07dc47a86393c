// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/RefinedSolve.h"

#include <algorithm>
#include <cmath>

namespace faceplan {

using RowMajorDense = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

Status RefinedSolve(const CondensedSystem& sys, const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                    bool concurrent, double tolerance, int maxSteps, double& worst, int& steps,
                    const RowMajorSparse* fullRowMajor, const Eigen::MatrixXd* initial) {
  auto solve = [&](const Eigen::MatrixXd& rhs, Eigen::MatrixXd& out) {
    return concurrent ? sys.factor.solveConcurrently(rhs, out) : sys.factor.solve(rhs, out);
  };
  Status s = Status::Ok();
  if (initial)
    x = *initial;
  else
    s = solve(b, x);
  if (!s)
    return s;
  const Eigen::VectorXd norms = b.colwise().norm().transpose();
  steps = 0;
  for (;;) {
    Eigen::MatrixXd residual;
    if (fullRowMajor && b.cols() > 1) {
      const RowMajorDense xr = x;
      residual = b - Eigen::MatrixXd(RowMajorDense(*fullRowMajor * xr));
    } else {
      residual = b - sys.kff.selfadjointView<Eigen::Upper>() * x;
    }
    worst = 0.0;
    for (Eigen::Index c = 0; c < b.cols(); ++c) {
      const double r = residual.col(c).norm();
      worst = std::max(worst, norms[c] > 0.0 ? r / norms[c] : r);
    }
    if (!std::isfinite(worst) || worst <= tolerance || steps >= maxSteps)
      break;
    Eigen::MatrixXd correction;
    s = solve(residual, correction);
    if (!s)
      return s;
    x += correction;
    ++steps;
  }
  return Status::Ok();
}

Status CachedLoadResponse(const CondensedSystem& sys, const Eigen::VectorXd& load,
                          Eigen::VectorXd& response, double& residual, int& steps) {
  std::lock_guard<std::mutex> lock(sys.loadMutex);
  residual = 0.0;
  steps = 0;
  if (sys.lastLoad.size() != load.size() || sys.lastLoad != load) {
    Eigen::MatrixXd x;
    Status s = RefinedSolve(sys, load, x, false, sys.residualTolerance, sys.maxRefinementSteps,
                            residual, steps);
    if (!s)
      return s;
    sys.lastLoad = load;
    sys.lastLoadResponse = x.col(0);
  }
  response = sys.lastLoadResponse;
  return Status::Ok();
}

} // namespace faceplan
