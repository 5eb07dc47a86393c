// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/SinglePrecisionCholesky.h"

#include "Common/ExceptionBoundary.h"
#include <Eigen/SparseCholesky>

namespace faceplan {

struct SinglePrecisionCholesky::Impl {
  const FreeSystem* system = nullptr;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<float, Eigen::ColMajor, int>, Eigen::Upper,
                       Eigen::AMDOrdering<int>>
      llt;
  double factorizeMs = 0.0;
};

SinglePrecisionCholesky::SinglePrecisionCholesky() : impl_(std::make_unique<Impl>()) {}
SinglePrecisionCholesky::~SinglePrecisionCholesky() = default;
double SinglePrecisionCholesky::factorizeMs() const {
  return impl_->factorizeMs;
}

Status SinglePrecisionCholesky::factorize(const FreeSystem& system) {
  return ReturnStatusOnException("the single-precision factorization", [&]() -> Status {
    StageClock clock;
    impl_->system = nullptr;
    const Eigen::SparseMatrix<float, Eigen::ColMajor, int> single = system.kff.cast<float>();
    impl_->llt.compute(single);
    impl_->factorizeMs = clock.elapsedMs();
    if (impl_->llt.info() != Eigen::Success)
      return Status::Error(
          "single-precision Cholesky failed: K_FF is not positive definite in float");
    impl_->system = &system;
    return Status::Ok();
  });
}

Status SinglePrecisionCholesky::solve(const Eigen::VectorXd& b, int refinementSteps,
                                      Eigen::VectorXd& x, SinglePrecisionReport& report) const {
  return ReturnStatusOnException("the single-precision solve", [&]() -> Status {
    report = SinglePrecisionReport();
    if (!impl_->system)
      return Status::Error("single-precision solve before a successful factorization");
    const FreeSystem& s = *impl_->system;
    if (b.size() != s.freeDofs())
      return Status::Error("right-hand side has the wrong size");
    StageClock clock;
    x = impl_->llt.solve(Eigen::VectorXf(b.cast<float>())).cast<double>();
    for (int k = 0; k < refinementSteps; ++k) {
      const Eigen::VectorXd r = b - s.kff.selfadjointView<Eigen::Upper>() * x;
      x += impl_->llt.solve(Eigen::VectorXf(r.cast<float>())).cast<double>();
    }
    report.solveMs = clock.elapsedMs();
    if (!x.allFinite())
      return Status::Error("single-precision solve produced non-finite values");
    report.relativeResidual = FreeRelativeResidual(s, x, b);
    return Status::Ok();
  });
}

} // namespace faceplan
