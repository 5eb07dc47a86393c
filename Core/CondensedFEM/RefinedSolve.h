// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Solves with the cached factor of K_FF, refined in double precision until the residual meets the
// tolerance. Shared by the precompute's response and the per-edit solves.
#include "CondensedFEM/CondensedSystem.h"

namespace faceplan {

using RowMajorSparse = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

// x = K_FF^-1 b with double-precision iterative refinement: while a column's relative residual
// exceeds `tolerance`, solve for the residual and correct (at most `maxSteps` times). `worst`
// receives the largest relative residual after refinement and `steps` the refinement steps taken.
// `fullRowMajor`, when given, is K_FF with both triangles in row-major storage: a product with
// many right-hand sides then streams each row once (faster than the symmetric view; BENCHMARKS.md).
// `initial`, when given, is used as the first solution instead of solving for b.
Status RefinedSolve(const CondensedSystem& sys, const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                    bool concurrent, double tolerance, int maxSteps, double& worst, int& steps,
                    const RowMajorSparse* fullRowMajor = nullptr,
                    const Eigen::MatrixXd* initial = nullptr);

// The free DOFs' response to `load` (K_FF^-1 load, refined), solved when the load differs from
// the last one and reused while it does not. `residual` and `steps` are that solve's (0 if reused).
Status CachedLoadResponse(const CondensedSystem& sys, const Eigen::VectorXd& load,
                          Eigen::VectorXd& response, double& residual, int& steps);

} // namespace faceplan
