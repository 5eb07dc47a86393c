// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/ConjugateGradientSolve.h"

#include "Common/ExceptionBoundary.h"
#include <Eigen/IterativeLinearSolvers>
#include <cmath>
#include <variant>

namespace faceplan {

const char* CGPreconditionerName(CGPreconditioner p) {
  return p == CGPreconditioner::Jacobi ? "Jacobi" : "IncompleteCholesky";
}

namespace {
template <class Scalar> using Matrix = Eigen::SparseMatrix<Scalar, Eigen::ColMajor, int>;
template <class Scalar>
using JacobiCG =
    Eigen::ConjugateGradient<Matrix<Scalar>, Eigen::Upper, Eigen::DiagonalPreconditioner<Scalar>>;
template <class Scalar>
using IcholCG = Eigen::ConjugateGradient<
    Matrix<Scalar>, Eigen::Upper,
    Eigen::IncompleteCholesky<Scalar, Eigen::Upper, Eigen::AMDOrdering<int>>>;
} // namespace

struct ConjugateGradientSolver::Impl {
  const FreeSystem* system = nullptr;
  CGOptions options;
  double setupMs = 0.0;
  Matrix<float> kffSingle;
  std::variant<std::monostate, JacobiCG<double>, IcholCG<double>, JacobiCG<float>, IcholCG<float>>
      cg;
};

ConjugateGradientSolver::ConjugateGradientSolver() : impl_(std::make_unique<Impl>()) {}
ConjugateGradientSolver::~ConjugateGradientSolver() = default;
double ConjugateGradientSolver::setupMs() const {
  return impl_->setupMs;
}

namespace {
template <class Solver, class Mat> Status Compute(Solver& solver, const Mat& matrix) {
  solver.compute(matrix);
  if (solver.info() != Eigen::Success)
    return Status::Error("preconditioner setup failed (not positive definite?)");
  return Status::Ok();
}
} // namespace

Status ConjugateGradientSolver::setup(const FreeSystem& system, const CGOptions& options) {
  return ReturnStatusOnException("the CG setup", [&]() -> Status {
    StageClock clock;
    Impl& m = *impl_;
    m.system = &system;
    m.options = options;
    m.cg = std::monostate{};
    Status s;
    const bool ichol = options.preconditioner == CGPreconditioner::IncompleteCholesky;
    if (options.precision == CGPrecision::Double) {
      if (ichol)
        s = Compute(m.cg.emplace<IcholCG<double>>(), system.kff);
      else
        s = Compute(m.cg.emplace<JacobiCG<double>>(), system.kff);
    } else {
      m.kffSingle = system.kff.cast<float>();
      if (ichol)
        s = Compute(m.cg.emplace<IcholCG<float>>(), m.kffSingle);
      else
        s = Compute(m.cg.emplace<JacobiCG<float>>(), m.kffSingle);
    }
    m.setupMs = clock.elapsedMs();
    return s;
  });
}

namespace {
template <class Solver>
void Run(Solver& solver, const Eigen::VectorXd& b, double tolerance, const Eigen::VectorXd* guess,
         int maxIterations, Eigen::VectorXd& x, CGReport& report) {
  using Scalar = typename Solver::Scalar;
  using Vec = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  solver.setTolerance(static_cast<typename Solver::RealScalar>(tolerance));
  if (maxIterations > 0)
    solver.setMaxIterations(maxIterations);
  const Vec bs = b.template cast<Scalar>();
  Vec xs;
  if (guess && guess->size() == b.size())
    xs = solver.solveWithGuess(bs, Vec(guess->template cast<Scalar>()));
  else
    xs = solver.solve(bs);
  x = xs.template cast<double>();
  report.iterations = static_cast<int>(solver.iterations());
  report.estimatedResidual = static_cast<double>(solver.error());
  report.converged = solver.info() == Eigen::Success;
}
} // namespace

Status ConjugateGradientSolver::solve(const Eigen::VectorXd& b, double tolerance,
                                      const Eigen::VectorXd* guess, Eigen::VectorXd& x,
                                      CGReport& report) const {
  return ReturnStatusOnException("the CG solve", [&]() -> Status {
    report = CGReport();
    const Impl& m = *impl_;
    if (!m.system)
      return Status::Error("CG solve before setup");
    if (b.size() != m.system->freeDofs())
      return Status::Error("CG right-hand side has the wrong size");
    if (!(tolerance > 0.0))
      return Status::Error("CG tolerance must be positive");
    StageClock clock;
    if (b.squaredNorm() == 0.0) {
      x = Eigen::VectorXd::Zero(b.size());
      report.converged = true;
      return Status::Ok();
    }
    auto& cg = const_cast<Impl&>(m).cg; // Eigen's solve is const; setTolerance is not
    std::visit(
        [&](auto& solver) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(solver)>, std::monostate>)
            Run(solver, b, tolerance, guess, m.options.maxIterations, x, report);
        },
        cg);
    report.solveMs = clock.elapsedMs();
    if (!x.allFinite())
      return Status::Error("CG produced non-finite values");
    report.relativeResidual = FreeRelativeResidual(*m.system, x, b);
    return Status::Ok();
  });
}

} // namespace faceplan
