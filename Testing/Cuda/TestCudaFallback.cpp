// SPDX-License-Identifier: BSD-3-Clause
// Runs on every machine (label `cuda`): the CUDA backend either works or refuses with a message,
// so that callers can fall back to the CPU; it never throws or aborts.
#include "Common/RelativeDifference.h"
#include "CudaBackend.h"
#include "CudaDenseResponse.h"

#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Support/ShellMeshGenerator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>

namespace faceplan {
namespace {

TEST(CudaFallback, BackendIsUsableOrRefusesWithAMessage) {
  std::string why;
  const bool available = cuda::DeviceAvailable(&why);
  std::shared_ptr<ComputeBackend> backend;
  const Status made = cuda::MakeCudaBackend(backend);
  const std::string& error = made.message;
  if (available) {
    ASSERT_TRUE(made && backend) << error;
    EXPECT_EQ(backend->name().rfind("CUDA", 0), 0u);
    EXPECT_FALSE(cuda::DeviceDescription().empty());
  } else {
    EXPECT_FALSE(backend);
    EXPECT_FALSE(why.empty());
    EXPECT_FALSE(error.empty());
    std::printf("no GPU: %s\n", error.c_str());
  }
}

TEST(CudaFallback, DisabledByEnvironment) {
  setenv("FACEPLAN_DISABLE_CUDA", "1", 1);
  std::shared_ptr<ComputeBackend> backend;
  const Status made = cuda::MakeCudaBackend(backend);
  const std::string& error = made.message;
  unsetenv("FACEPLAN_DISABLE_CUDA");
  EXPECT_FALSE(made);
  EXPECT_FALSE(backend);
  EXPECT_NE(error.find("FACEPLAN_DISABLE_CUDA"), std::string::npos) << error;
}

// The CPU backend with a factorAndBuildResponse hook: the CUDA one (GPU factorization + response;
// fails without a GPU) or a stub that fails with or without having factorized.
class HookBackend final : public ComputeBackend {
public:
  enum class Hook { Cuda, FailBeforeFactor, FailAfterFactor, LargeResidual };
  explicit HookBackend(Hook hook) : hook_(hook) {}
  std::string name() const override { return "Hooked"; }
  Status assembleStiffness(const TetMesh& mesh, const Materials& materials,
                           AssemblyPattern& pattern, AssemblyTimings& timings) override {
    return cpu_->assembleStiffness(mesh, materials, pattern, timings);
  }
  Status makeResponseOperator(const Eigen::MatrixXd& response,
                              std::unique_ptr<ResponseOperator>& op) override {
    return cpu_->makeResponseOperator(response, op);
  }
  bool providesFactorAndResponse() const override { return true; }
  Status factorAndBuildResponse(const SparseMatrix& kff, const SparseMatrix& kfr,
                                Eigen::Index keptDofs, CholmodFactor& factor,
                                Eigen::MatrixXd& response, std::unique_ptr<ResponseOperator>& op,
                                FactorResponseReport& report) override {
    ++calls;
    switch (hook_) {
    case Hook::Cuda: {
      cuda::FactorAndResponseDetail detail;
      const Status status =
          cuda::FactorAndBuildResponse(kff, kfr, keptDofs, factor, response, op, detail);
      report.factorizationMs = detail.factorizeMs + detail.factorDownloadWaitMs;
      report.worstRelativeResidual = detail.response.worstRelativeResidual;
      return status;
    }
    case Hook::FailBeforeFactor:
      response = Eigen::MatrixXd::Constant(2, 2, 1.0); // garbage the caller must discard
      return Status::Error("simulated device failure");
    case Hook::FailAfterFactor:
    case Hook::LargeResidual: {
      const Status s = factor.factorize(kff);
      EXPECT_TRUE(s.ok) << s.message;
      if (hook_ == Hook::FailAfterFactor) {
        return Status::Error("simulated failure after the factorization");
      }
      response =
          Eigen::MatrixXd::Zero(keptDofs, kfr.cols()); // wrong values, flagged by the residual
      report.worstRelativeResidual = 1.0;
      return Status::Ok();
    }
    }
    return Status::Error("unknown hook");
  }
  int calls = 0;

private:
  Hook hook_;
  std::shared_ptr<ComputeBackend> cpu_ = MakeCpuBackend();
};

// Precompute with a backend whose factorization/response hook fails (no GPU, or a simulated
// failure) falls back to the CPU with a warning, and solves exactly as the CPU backend does.
TEST(CudaFallback, PrecomputeFallsBackWhenTheFactorResponseHookFails) {
  const FaceLikeScene scene = MakeFaceLikeScene(5, 3, 0.15);
  PrecomputeRequest request;
  request.mesh = scene.shell.mesh;
  request.materials = Materials::Uniform(3.0e3, 0.45);
  request.sets.constrained = scene.constrained;
  request.sets.movable = scene.movable;
  request.sets.kept = scene.kept;
  request.options.method = SolveMethod::DenseResponse;
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(scene.movable.size()), 3);
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 0.01);
  for (Eigen::Index i = 0; i < input.movableDisplacement.size(); ++i)
    input.movableDisplacement.data()[i] = normal(rng);

  std::shared_ptr<const CondensedSystem> reference;
  request.options.backend = MakeCpuBackend();
  ASSERT_FALSE(request.options.backend->providesFactorAndResponse());
  ASSERT_TRUE(Precompute(request, reference).ok);
  SolveResult expected;
  ASSERT_TRUE(Solve(*reference, input, expected).ok);

  const bool gpu = cuda::DeviceAvailable();
  using Hook = HookBackend::Hook;
  for (Hook hook :
       {Hook::Cuda, Hook::FailBeforeFactor, Hook::FailAfterFactor, Hook::LargeResidual}) {
    SCOPED_TRACE(static_cast<int>(hook));
    auto backend = std::make_shared<HookBackend>(hook);
    request.options.backend = backend;
    std::shared_ptr<const CondensedSystem> system;
    const Status pre = Precompute(request, system);
    ASSERT_TRUE(pre.ok) << pre.message;
    EXPECT_EQ(backend->calls, 1);
    const bool expectFallback = hook != Hook::Cuda || !gpu;
    std::string warnings;
    for (const std::string& w : pre.warnings)
      warnings += w + "\n";
    EXPECT_EQ(warnings.find("factorization/response failed") != std::string::npos, expectFallback)
        << warnings;
    if (hook == Hook::Cuda && !gpu)
      EXPECT_NE(warnings.find("factorized and built the response on the CPU"), std::string::npos)
          << warnings;
    if (hook == Hook::FailBeforeFactor)
      EXPECT_NE(warnings.find("simulated device failure"), std::string::npos) << warnings;
    if (hook == Hook::FailAfterFactor || hook == Hook::LargeResidual)
      EXPECT_NE(warnings.find("the response was built on the CPU"), std::string::npos) << warnings;
    if (hook == Hook::LargeResidual)
      EXPECT_NE(warnings.find("residual"), std::string::npos) << warnings;
    EXPECT_TRUE(system->factor.isFactorized());
    EXPECT_LE(RelativeMaxDifference(system->response, reference->response), 1e-10);
    EXPECT_LE(system->responseResidual, 1e-10);
    SolveResult result;
    const Status solved = Solve(*system, input, result);
    ASSERT_TRUE(solved.ok) << solved.message;
    EXPECT_LE(RelativeMaxDifference(result.keptDisplacement, expected.keptDisplacement), 1e-10);
  }
}

} // namespace
} // namespace faceplan
