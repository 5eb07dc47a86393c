// SPDX-License-Identifier: BSD-3-Clause
// GPU-against-CPU agreement of the CUDA backend. CTest label `gpu`.
// Without a usable GPU every case is skipped (GTEST_SKIP), never passed.
#include "CudaBackend.h"
#include "CudaTestGpu.h"
#include "CudaTestMesh.h"

#include "Backend/ComputeBackend.h"
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/CondensedSystem.h"
#include "CudaDenseResponse.h"
#include "Element/ElementStiffness.h"
#include "Element/StiffnessAssembly.h"
#include "Support/ShellMeshGenerator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <thread>

namespace faceplan {
namespace {

using faceplan::testing::Gpu;

Materials RandomMaterials(Eigen::Index cells, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> logE(std::log(1e3), std::log(2e10)), nu(0.0, 0.49);
  Materials materials;
  materials.youngsModulus.resize(cells);
  materials.poissonRatio.resize(cells);
  for (Eigen::Index c = 0; c < cells; ++c) {
    materials.youngsModulus[c] = std::exp(logE(rng));
    materials.poissonRatio[c] = nu(rng);
  }
  return materials;
}

// The face-like shell's precompute request: random per-cell materials, the scene's node sets.
PrecomputeRequest ShellRequest(const FaceLikeScene& scene, unsigned materialSeed,
                               SolveMethod method) {
  PrecomputeRequest request;
  request.mesh = scene.shell.mesh;
  request.materials = RandomMaterials(request.mesh.numTets(), materialSeed);
  request.sets.constrained = scene.constrained;
  request.sets.movable = scene.movable;
  request.sets.kept = scene.kept;
  request.options.method = method;
  return request;
}

// dofNode: a random permutation of the nodes, with every `dropEvery`-th node dropped (-1).
std::vector<int> RandomNumbering(Eigen::Index nodes, unsigned seed, int dropEvery,
                                 int& numDofNodes) {
  std::vector<int> order(nodes);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  std::vector<int> dofNode(nodes, -1);
  numDofNodes = 0;
  for (Eigen::Index i = 0; i < nodes; ++i)
    if (dropEvery <= 0 || i % dropEvery != 0)
      dofNode[order[i]] = numDofNodes++;
  return dofNode;
}

// Assembles with the CPU backend and the GPU backend into copies of `pattern`; returns the
// relative difference. The GPU copy is poisoned with NaN first so unwritten values show.
double CompareAssembly(ComputeBackend& gpu, const TetMesh& mesh, const Materials& materials,
                       AssemblyPattern& gpuPattern, const AssemblyPattern& pattern) {
  AssemblyPattern cpuPattern = pattern;
  ComputeBackend::AssemblyTimings cpuTimings, gpuTimings;
  const Status cpu = MakeCpuBackend()->assembleStiffness(mesh, materials, cpuPattern, cpuTimings);
  EXPECT_TRUE(cpu) << cpu.message;
  std::fill(gpuPattern.upper.valuePtr(), gpuPattern.upper.valuePtr() + gpuPattern.upper.nonZeros(),
            std::numeric_limits<double>::quiet_NaN());
  const Status assembled = gpu.assembleStiffness(mesh, materials, gpuPattern, gpuTimings);
  EXPECT_TRUE(assembled) << assembled.message;
  EXPECT_GE(gpuTimings.elementStiffnessMs, 0.0);
  EXPECT_GE(gpuTimings.assemblyMs, 0.0);
  return RelativeMaxDifference(gpuPattern.upper.valuePtr(), cpuPattern.upper.valuePtr(),
                               static_cast<size_t>(cpuPattern.upper.nonZeros()));
}

TEST(CudaBackend, AssembledStiffnessMatchesCpuPerCellMaterials) {
  REQUIRE_GPU_OR_SKIP();
  auto gpu = Gpu();
  ASSERT_TRUE(gpu);
  EXPECT_EQ(gpu->name().rfind("CUDA", 0), 0u) << gpu->name();
  const TetMesh mesh = testing::MakePerturbedBox(9, 8, 7, 11);
  int numDofNodes = 0;
  const std::vector<int> dofNode = RandomNumbering(mesh.numPoints(), 5, 7, numDofNodes);
  AssemblyPattern pattern;

  ASSERT_TRUE(BuildAssemblyPattern(mesh, dofNode, numDofNodes, pattern));
  AssemblyPattern gpuPattern = pattern;

  const double first =
      CompareAssembly(*gpu, mesh, RandomMaterials(mesh.numTets(), 1), gpuPattern, pattern);
  EXPECT_LE(first, 1e-12);
  cuda::AssemblyDetail detail;
  ASSERT_TRUE(cuda::LastAssemblyDetail(*gpu, detail));
  EXPECT_FALSE(detail.patternReused);

  // Same pattern object again with new materials: the cached gather map is reused and the new
  // materials are used.
  const double second =
      CompareAssembly(*gpu, mesh, RandomMaterials(mesh.numTets(), 2), gpuPattern, pattern);
  EXPECT_LE(second, 1e-12);
  ASSERT_TRUE(cuda::LastAssemblyDetail(*gpu, detail));
  EXPECT_TRUE(detail.patternReused);
  EXPECT_GT(detail.kernelBytes, 0.0);
  std::printf("relative max difference GPU vs CPU: %.3e, %.3e\n", first, second);
}

TEST(CudaBackend, AssembledStiffnessMatchesCpuUniformMaterialAndNewPattern) {
  REQUIRE_GPU_OR_SKIP();
  auto gpu = Gpu();
  ASSERT_TRUE(gpu);
  TetMesh mesh = testing::MakePerturbedBox(12, 5, 6, 21);
  const Materials uniform = Materials::Uniform(3.0e3, 0.45);
  for (unsigned seed : {1u, 2u}) {
    int numDofNodes = 0;
    const std::vector<int> dofNode =
        RandomNumbering(mesh.numPoints(), 100 + seed, seed == 1 ? 0 : 5, numDofNodes);
    AssemblyPattern pattern;

    ASSERT_TRUE(BuildAssemblyPattern(mesh, dofNode, numDofNodes, pattern));
    AssemblyPattern gpuPattern = pattern;
    EXPECT_LE(CompareAssembly(*gpu, mesh, uniform, gpuPattern, pattern), 1e-12)
        << "numbering " << seed;
  }
  // Moved points with the same pattern: the new coordinates are used.
  int numDofNodes = 0;
  const std::vector<int> dofNode = RandomNumbering(mesh.numPoints(), 7, 0, numDofNodes);
  AssemblyPattern pattern;

  ASSERT_TRUE(BuildAssemblyPattern(mesh, dofNode, numDofNodes, pattern));
  AssemblyPattern gpuPattern = pattern;
  EXPECT_LE(CompareAssembly(*gpu, mesh, uniform, gpuPattern, pattern), 1e-12);
  mesh.points *= 1.7;
  mesh.points.col(2).array() += 0.3;
  EXPECT_LE(CompareAssembly(*gpu, mesh, uniform, gpuPattern, pattern), 1e-12);
}

TEST(CudaBackend, SingleTetrahedronEqualsTetStiffness) {
  REQUIRE_GPU_OR_SKIP();
  auto gpu = Gpu();
  ASSERT_TRUE(gpu);
  TetMesh mesh;
  mesh.points.resize(4, 3);
  mesh.points << 0.1, 0.0, 0.2, 1.3, 0.1, 0.0, 0.2, 0.9, 0.1, 0.3, 0.2, 1.4;
  mesh.tets.resize(1, 4);
  mesh.tets << 0, 1, 2, 3;
  AssemblyPattern pattern;

  ASSERT_TRUE(BuildAssemblyPattern(mesh, {0, 1, 2, 3}, 4, pattern));
  ComputeBackend::AssemblyTimings timings;
  const Status status =
      gpu->assembleStiffness(mesh, Materials::Uniform(1000.0, 0.3), pattern, timings);
  ASSERT_TRUE(status) << status.message;
  const Eigen::MatrixXd assembled = Eigen::MatrixXd(pattern.upper).selfadjointView<Eigen::Upper>();
  const ElementMatrix ke = TetStiffness(mesh.points.cast<double>(), 1000.0, 0.3);
  EXPECT_LE(RelativeMaxDifference(assembled, ke), 1e-13);
}

TEST(CudaBackend, ResponseApplyMatchesCpuFromSeveralThreads) {
  REQUIRE_GPU_OR_SKIP();
  auto gpu = Gpu();
  ASSERT_TRUE(gpu);
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd response(1537, 401);
  for (Eigen::Index i = 0; i < response.size(); ++i)
    response.data()[i] = normal(rng);
  std::unique_ptr<ResponseOperator> op;
  const Status made = gpu->makeResponseOperator(response, op);
  ASSERT_TRUE(made && op) << made.message;

  std::vector<Eigen::VectorXd> inputs(64);
  for (auto& v : inputs) {
    v.resize(response.cols());
    for (Eigen::Index i = 0; i < v.size(); ++i)
      v[i] = normal(rng);
  }
  std::vector<double> worst(4, 0.0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 25; ++rep) {
        const Eigen::VectorXd& roi = inputs[(t * 25 + rep) % inputs.size()];
        Eigen::VectorXd kept = Eigen::VectorXd::Constant(3, std::nan(""));
        if (!op->apply(roi, kept)) {
          worst[t] = std::numeric_limits<double>::infinity();
          return;
        }
        const Eigen::VectorXd reference = response * roi;
        if (kept.size() != reference.size()) {
          worst[t] = std::numeric_limits<double>::infinity();
          return;
        }
        worst[t] =
            std::max(worst[t], RelativeMaxDifference(kept.data(), reference.data(), kept.size()));
      }
    });
  }
  for (auto& th : threads)
    th.join();
  for (double w : worst)
    EXPECT_LE(w, 1e-12);

  Eigen::VectorXd kept;
  const Status wrongSize = op->apply(Eigen::VectorXd::Zero(5), kept);
  EXPECT_FALSE(wrongSize);
  EXPECT_FALSE(wrongSize.message.empty());
}

TEST(CudaBackend, EmptyResponse) {
  REQUIRE_GPU_OR_SKIP();
  auto gpu = Gpu();
  ASSERT_TRUE(gpu);
  std::unique_ptr<ResponseOperator> op;
  const Status made = gpu->makeResponseOperator(Eigen::MatrixXd::Zero(7, 0), op);
  ASSERT_TRUE(made && op) << made.message;
  Eigen::VectorXd kept;
  const Status applied = op->apply(Eigen::VectorXd(0), kept);
  ASSERT_TRUE(applied) << applied.message;
  EXPECT_EQ(kept.size(), 7);
  EXPECT_EQ(kept.cwiseAbs().maxCoeff(), 0.0);
}

// The whole precompute/solve with the CUDA backend against the CPU backend.
void CompareFullPipeline(SolveMethod method) {
  const FaceLikeScene scene = MakeFaceLikeScene(6, 3, 0.15);
  PrecomputeRequest request = ShellRequest(scene, 9, method);

  std::mt19937 rng(4);
  std::normal_distribution<double> normal(0.0, 0.01);
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(scene.movable.size()), 3);
  for (Eigen::Index i = 0; i < input.movableDisplacement.size(); ++i)
    input.movableDisplacement.data()[i] = normal(rng);

  SolveResult results[2];
  for (int b = 0; b < 2; ++b) {
    Status made;
    if (b == 0)
      request.options.backend = MakeCpuBackend();
    else
      made = cuda::MakeCudaBackend(request.options.backend);
    ASSERT_TRUE(made && request.options.backend) << made.message;
    std::shared_ptr<const CondensedSystem> system;
    const Status pre = Precompute(request, system);
    ASSERT_TRUE(pre.ok) << pre.message;
    const Status solved = Solve(*system, input, results[b]);
    ASSERT_TRUE(solved.ok) << solved.message;
    if (b == 1) {
      EXPECT_NE(Describe(*system).backend.find("CUDA"), std::string::npos)
          << Describe(*system).backend;
      EXPECT_TRUE(pre.warnings.empty()) << pre.warnings.front(); // no fallback to the CPU
      cuda::FactorAndResponseDetail detail;
      // DenseResponse: the numeric factorization and the response ran on the GPU.
      EXPECT_EQ(cuda::LastFactorAndResponseDetail(*request.options.backend, detail) &&
                    detail.succeeded,
                method == SolveMethod::DenseResponse);
    }
  }
  ASSERT_EQ(results[0].keptDisplacement.rows(), static_cast<Eigen::Index>(scene.kept.size()));
  ASSERT_EQ(results[1].keptDisplacement.rows(), results[0].keptDisplacement.rows());
  const double diff =
      RelativeMaxDifference(results[1].keptDisplacement.data(), results[0].keptDisplacement.data(),
                            static_cast<size_t>(results[0].keptDisplacement.size()));
  EXPECT_LE(diff, 1e-10) << MethodName(method);
  EXPECT_GT(results[0].keptDisplacement.cwiseAbs().maxCoeff(), 0.0);
  std::printf("%s: relative max difference of kept displacements GPU vs CPU: %.3e\n",
              MethodName(method), diff);
}

TEST(CudaBackend, PrecomputeAndSolveDenseResponseMatchCpu) {
  REQUIRE_GPU_OR_SKIP();
  CompareFullPipeline(SolveMethod::DenseResponse);
}

TEST(CudaBackend, PrecomputeAndSolveCachedFactorMatchCpu) {
  REQUIRE_GPU_OR_SKIP();
  CompareFullPipeline(SolveMethod::CachedFactor);
}

// Precompute() with the CUDA backend and DenseResponse runs the numeric factorization and the
// response on the GPU (the backend's factorAndBuildResponse hook), without falling back: its
// response, its factor (loads) and its solve equal the CPU backend's.
TEST(CudaBackend, PrecomputeUsesGpuFactorizationAndResponse) {
  REQUIRE_GPU_OR_SKIP();
  const FaceLikeScene scene = MakeFaceLikeScene(7, 4, 0.12);
  PrecomputeRequest request = ShellRequest(scene, 31, SolveMethod::DenseResponse);
  request.materials.density = Eigen::VectorXd::Constant(request.mesh.numTets(), 1000.0);

  std::shared_ptr<const CondensedSystem> cpuSystem, gpuSystem;
  request.options.backend = MakeCpuBackend();
  const Status cpuPre = Precompute(request, cpuSystem);
  ASSERT_TRUE(cpuPre.ok) << cpuPre.message;
  auto gpu = Gpu();
  ASSERT_TRUE(gpu);
  ASSERT_TRUE(gpu->providesFactorAndResponse());
  request.options.backend = gpu;
  const Status gpuPre = Precompute(request, gpuSystem);
  ASSERT_TRUE(gpuPre.ok) << gpuPre.message;
  for (const std::string& w : gpuPre.warnings)
    ADD_FAILURE() << "warning: " << w;

  cuda::FactorAndResponseDetail detail;
  ASSERT_TRUE(cuda::LastFactorAndResponseDetail(*gpu, detail));
  EXPECT_TRUE(detail.succeeded);
  EXPECT_EQ(detail.call, 1);
  EXPECT_GT(detail.factorizeMs, 0.0);
  EXPECT_GT(detail.response.supernodes, 0);
  EXPECT_GT(detail.response.worstRelativeResidual, 0.0); // the residual check ran
  EXPECT_LE(detail.response.worstRelativeResidual, 1e-10);
  const SystemInfo info = Describe(*gpuSystem);
  EXPECT_EQ(info.method, SolveMethod::DenseResponse);
  EXPECT_NE(info.backend.find("CUDA"), std::string::npos) << info.backend;
  EXPECT_GT(info.precomputeTimings[Stage::Factorization].ms, 0.0);
  EXPECT_GT(info.precomputeTimings[Stage::Condensation].ms, 0.0);
  EXPECT_TRUE(gpuSystem->factor.isFactorized());
  EXPECT_EQ(gpuSystem->responseResidual, detail.response.worstRelativeResidual);

  ASSERT_EQ(gpuSystem->response.rows(), cpuSystem->response.rows());
  ASSERT_EQ(gpuSystem->response.cols(), cpuSystem->response.cols());
  const double responseDiff =
      RelativeMaxDifference(gpuSystem->response.data(), cpuSystem->response.data(),
                            static_cast<size_t>(cpuSystem->response.size()));
  EXPECT_LE(responseDiff, 1e-10);

  // Solve with prescribed ROI displacements, gravity and nodal loads (the loads go through the
  // GPU-computed factor copied into CHOLMOD).
  std::mt19937 rng(8);
  std::normal_distribution<double> normal(0.0, 0.01);
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(scene.movable.size()), 3);
  for (Eigen::Index i = 0; i < input.movableDisplacement.size(); ++i)
    input.movableDisplacement.data()[i] = normal(rng);
  input.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  input.nodalLoads = Eigen::MatrixXd::Zero(request.mesh.numPoints(), 3);
  for (Eigen::Index i = 0; i < input.nodalLoads.rows(); i += 7)
    input.nodalLoads.row(i) << 0.0, 0.0, 1e-3;
  SolveResult cpuResult, gpuResult;
  ASSERT_TRUE(Solve(*cpuSystem, input, cpuResult).ok);
  const Status solved = Solve(*gpuSystem, input, gpuResult);
  ASSERT_TRUE(solved.ok) << solved.message;
  ASSERT_EQ(gpuResult.keptDisplacement.size(), cpuResult.keptDisplacement.size());
  const double solveDiff =
      RelativeMaxDifference(gpuResult.keptDisplacement.data(), cpuResult.keptDisplacement.data(),
                            static_cast<size_t>(cpuResult.keptDisplacement.size()));
  EXPECT_LE(solveDiff, 1e-10);
  EXPECT_GT(cpuResult.keptDisplacement.cwiseAbs().maxCoeff(), 0.0);
  std::printf("Precompute with GPU factorization + response: response vs CPU %.3e, solve vs CPU "
              "%.3e, residual %.3e, "
              "factorization %.1f ms, condensation %.1f ms\n",
              responseDiff, solveDiff, detail.response.worstRelativeResidual,
              info.precomputeTimings[Stage::Factorization].ms,
              info.precomputeTimings[Stage::Condensation].ms);
}

// The dense response built with GPU triangular solves equals Core's CPU response, in one pass and
// in several passes over the ROI columns, and its operator applies it.
TEST(CudaBackend, DenseResponseOnGpuMatchesCoreResponse) {
  REQUIRE_GPU_OR_SKIP();
  const FaceLikeScene scene = MakeFaceLikeScene(6, 3, 0.15);
  PrecomputeRequest request = ShellRequest(scene, 12, SolveMethod::DenseResponse);
  std::shared_ptr<const CondensedSystem> system;
  const Status pre = Precompute(request, system);
  ASSERT_TRUE(pre.ok) << pre.message;
  ASSERT_EQ(system->method, SolveMethod::DenseResponse);
  const Eigen::MatrixXd& reference = system->response;
  ASSERT_GT(reference.size(), 0);

  cuda::SupernodalCholesky factor;
  const Status factored = factor.factor(system->kff);
  ASSERT_TRUE(factored) << factored.message;
  for (int maxColumns : {0, 17}) {
    Eigen::MatrixXd response = Eigen::MatrixXd::Constant(3, 3, std::nan(""));
    std::unique_ptr<ResponseOperator> op;
    cuda::DenseResponseDetail detail;
    const Status built =
        cuda::BuildDenseResponse(factor.view(), &system->kff, system->kfr, reference.rows(),
                                 &response, &op, detail, maxColumns);
    ASSERT_TRUE(built) << built.message;
    ASSERT_EQ(response.rows(), reference.rows());
    ASSERT_EQ(response.cols(), reference.cols());
    const double diff = RelativeMaxDifference(response.data(), reference.data(),
                                              static_cast<size_t>(reference.size()));
    EXPECT_LE(diff, 1e-10) << "maxColumns " << maxColumns;
    EXPECT_LE(detail.worstRelativeResidual, 1e-10);
    EXPECT_GT(detail.worstRelativeResidual, 0.0); // the check ran
    if (maxColumns > 0)
      EXPECT_GT(detail.blocks, 1);
    std::printf("GPU response (%d passes): relative difference %.3e, worst residual %.3e\n",
                detail.blocks, diff, detail.worstRelativeResidual);
    ASSERT_TRUE(op);
    std::mt19937 rng(maxColumns + 1);
    std::normal_distribution<double> normal;
    Eigen::VectorXd roi(reference.cols());
    for (Eigen::Index i = 0; i < roi.size(); ++i)
      roi[i] = normal(rng);
    Eigen::VectorXd kept;
    const Status applied = op->apply(roi, kept);
    ASSERT_TRUE(applied) << applied.message;
    const Eigen::VectorXd expected = reference * roi;
    EXPECT_LE(
        RelativeMaxDifference(kept.data(), expected.data(), static_cast<size_t>(expected.size())),
        1e-10);
  }
}

// GPU numeric factorization on CHOLMOD's symbolic structure: its CHOLMOD copy solves like a CPU
// factor, and the response built from the factor left on the GPU matches Core's.
TEST(CudaBackend, GpuFactorizationMatchesCholmod) {
  REQUIRE_GPU_OR_SKIP();
  const FaceLikeScene scene = MakeFaceLikeScene(7, 4, 0.12);
  PrecomputeRequest request = ShellRequest(scene, 21, SolveMethod::DenseResponse);
  std::shared_ptr<const CondensedSystem> system;
  const Status pre = Precompute(request, system);
  ASSERT_TRUE(pre.ok) << pre.message;

  cuda::SupernodalCholesky gpuFactor;
  const Status factored = gpuFactor.factorOnGpu(system->kff, true);
  ASSERT_TRUE(factored) << factored.message;
  ASSERT_NE(gpuFactor.view().deviceX, nullptr);
  ASSERT_NE(gpuFactor.view().x, nullptr);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd b(system->kff.rows(), 3);
  for (Eigen::Index i = 0; i < b.size(); ++i)
    b.data()[i] = normal(rng);
  Eigen::MatrixXd x;
  const Status solved = gpuFactor.solve(b, x);
  ASSERT_TRUE(solved) << solved.message;
  const double residual = (system->kff.selfadjointView<Eigen::Upper>() * x - b).norm() / b.norm();
  EXPECT_LE(residual, 1e-10);
  Eigen::MatrixXd reference;
  ASSERT_TRUE(system->factor.solve(b, reference).ok);
  EXPECT_LE(RelativeMaxDifference(x.data(), reference.data(), static_cast<size_t>(x.size())), 1e-9);

  Eigen::MatrixXd response;
  cuda::DenseResponseDetail detail;
  const Status built =
      cuda::BuildDenseResponse(gpuFactor.view(), &system->kff, system->kfr, system->response.rows(),
                               &response, nullptr, detail);
  ASSERT_TRUE(built) << built.message;
  EXPECT_LE(RelativeMaxDifference(response.data(), system->response.data(),
                                  static_cast<size_t>(response.size())),
            1e-9);
  EXPECT_LE(detail.worstRelativeResidual, 1e-10);
  std::printf("GPU factorization: solve residual %.3e, response residual %.3e\n", residual,
              detail.worstRelativeResidual);

  // A matrix that is not positive definite is refused with a message.
  SparseMatrix bad = system->kff;
  bad.coeffRef(5, 5) = -1.0;
  cuda::SupernodalCholesky badFactor;
  const Status refused = badFactor.factorOnGpu(bad);
  EXPECT_FALSE(refused);
  EXPECT_NE(refused.message.find("positive definite"), std::string::npos) << refused.message;
}

} // namespace
} // namespace faceplan
