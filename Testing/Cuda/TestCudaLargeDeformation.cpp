// SPDX-License-Identifier: BSD-3-Clause
// The large-deformation solve's steps on the GPU (CudaLargeDeformation.h) against the CPU's: the
// cells' energy and force, substitutions with a factor and tangent products, and whole solves and
// drags with the CUDA backend against the CPU's and Newton's. CTest label `gpu`; without a usable
// GPU every case is skipped (GTEST_SKIP), never passed.
#include "CudaBackend.h"
#include "CudaLargeDeformation.h"
#include "CudaTestGpu.h"
#include "CudaTestMesh.h"

#include "Common/RelativeDifference.h"
#include "CondensedFEM/LargeDeformation.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"
#include "Element/NeoHookeanTet.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/SinglePrecisionFactor.h"
#include "Support/FEMTestScenes.h"
#include "Support/PrecomputedSystem.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace faceplan {
namespace {

using faceplan::testing::Gpu;
using faceplan::testing::Precomputed;

// A perturbed box's cells with random moduli, a third of the nodes in random frames and every
// fifth cell small-strain, and its reference energy and force at u from Core's element routines.
struct Cells {
  TetMesh mesh;
  HyperelasticCells cells;
  std::vector<TetReference> references;
  std::vector<NeoHookeanParameters> parameters;
  std::vector<Eigen::Matrix3d> frames;

  explicit Cells(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), modulus(1e3, 5e4);
    mesh = testing::MakePerturbedBox(6, 5, 4, seed);
    const Eigen::Index m = mesh.numTets(), n = mesh.numPoints();
    cells.nodes = static_cast<int>(n);
    cells.frameOf.assign(static_cast<size_t>(n), -1);
    for (Eigen::Index i = 0; i < n; i += 3) {
      const Eigen::Matrix3d q =
          Eigen::Quaterniond(
              Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized())
              .toRotationMatrix();
      cells.frameOf[static_cast<size_t>(i)] = static_cast<int>(frames.size());
      frames.push_back(q);
      cells.frames.insert(cells.frames.end(), q.data(), q.data() + 9);
    }
    for (Eigen::Index e = 0; e < m; ++e) {
      TetCorners corners;
      for (int a = 0; a < 4; ++a) {
        corners.row(a) = mesh.points.row(mesh.tets(e, a));
        cells.corners.push_back(mesh.tets(e, a));
      }
      references.push_back(MakeTetReference(corners));
      parameters.push_back(NeoHookeanFromLinear(modulus(rng), 0.45));
      for (int a = 0; a < 4; ++a)
        for (int j = 0; j < 3; ++j)
          cells.gradients.push_back(references.back().gradients(a, j));
      cells.volume.push_back(references.back().volume);
      cells.mu.push_back(parameters.back().mu);
      cells.kappa.push_back(parameters.back().kappa);
      cells.smallStrain.push_back(e % 5 == 0 ? 1 : 0);
    }
  }

  Eigen::Vector3d toGlobal(Eigen::Index node, const Eigen::Vector3d& local) const {
    const int f = cells.frameOf[static_cast<size_t>(node)];
    return f < 0 ? local : Eigen::Vector3d(frames[f] * local);
  }

  bool reference(const Eigen::VectorXd& u, double& energy, Eigen::VectorXd& force) const {
    energy = 0.0;
    force.setZero(u.size());
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
      CornerDisplacements corner;
      for (int a = 0; a < 4; ++a)
        corner.row(a) = toGlobal(mesh.tets(e, a), u.segment<3>(3 * mesh.tets(e, a))).transpose();
      double cellEnergy = 0.0;
      ElementVector f;
      const bool ok =
          cells.smallStrain[e]
              ? SmallStrainTetState(references[e], parameters[e], corner, cellEnergy, f, nullptr)
              : NeoHookeanTetState(references[e], parameters[e], corner, cellEnergy, f, nullptr);
      if (!ok)
        return false;
      energy += cellEnergy;
      for (int a = 0; a < 4; ++a) {
        const int node = mesh.tets(e, a), frame = cells.frameOf[node];
        const Eigen::Vector3d fa = f.segment<3>(3 * a);
        force.segment<3>(3 * node) +=
            frame < 0 ? fa : Eigen::Vector3d(frames[frame].transpose() * fa);
      }
    }
    return true;
  }
};

TEST(CudaLargeDeformation, ForcesMatchCoreElements) {
  REQUIRE_GPU_OR_SKIP();
  auto backend = Gpu();
  ASSERT_TRUE(backend);
  const Cells c(7);
  std::unique_ptr<HyperelasticForces> forces;
  const Status made = backend->makeHyperelasticForces(c.cells, forces);
  ASSERT_TRUE(made) << made.message;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (double amplitude : {0.0, 0.01, 0.15}) {
    Eigen::VectorXd u(3 * c.cells.nodes);
    for (Eigen::Index i = 0; i < u.size(); ++i)
      u[i] = amplitude * unit(rng);
    double energy = 0.0, expectedEnergy = 0.0;
    Eigen::VectorXd force, expected;
    bool admissible = false;
    ASSERT_TRUE(c.reference(u, expectedEnergy, expected));
    ASSERT_TRUE(forces->evaluate(u, energy, force, admissible));
    ASSERT_TRUE(admissible);
    const double scale = std::max(expected.cwiseAbs().maxCoeff(), 1e-300);
    EXPECT_LE((force - expected).cwiseAbs().maxCoeff(), 1e-12 * scale) << amplitude;
    EXPECT_NEAR(energy, expectedEnergy, 1e-12 * std::max(std::abs(expectedEnergy), 1e-300));
    // The measures: the smallest det F, the largest absolute principal Green strain and its cell.
    double smallestDet = std::numeric_limits<double>::infinity(), largest = 0.0;
    for (Eigen::Index e = 0; e < c.mesh.numTets(); ++e) {
      CornerDisplacements corner;
      for (int a = 0; a < 4; ++a)
        corner.row(a) =
            c.toGlobal(c.mesh.tets(e, a), u.segment<3>(3 * c.mesh.tets(e, a))).transpose();
      const Eigen::Matrix3d F = DeformationGradient(c.references[e], corner);
      smallestDet = std::min(smallestDet, F.determinant());
      const Eigen::Matrix3d green = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
      largest = std::max(largest, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(green)
                                      .eigenvalues()
                                      .cwiseAbs()
                                      .maxCoeff());
    }
    double det = 0.0, strain = -1.0;
    long long cell = -2;
    ASSERT_TRUE(forces->measure(u, det, strain, cell));
    EXPECT_NEAR(det, smallestDet, 1e-12);
    EXPECT_NEAR(strain, largest, 1e-12 * std::max(1.0, largest)) << amplitude;
    if (amplitude == 0.0) {
      EXPECT_EQ(cell, -1);
    } else {
      ASSERT_GE(cell, 0);
      ASSERT_LT(cell, c.mesh.numTets());
      EXPECT_GT(strain, 1e-3);
    }
  }
  // One node pushed through its cells' opposite faces: an inverted cell is inadmissible.
  Eigen::VectorXd inverted = Eigen::VectorXd::Zero(3 * c.cells.nodes);
  const int node = c.mesh.tets(0, 0);
  const Eigen::Vector3d through = 50.0 * Eigen::Vector3d(1.0, 1.3, 0.7);
  const int frame = c.cells.frameOf[node];
  inverted.segment<3>(3 * node) =
      frame < 0 ? through : Eigen::Vector3d(c.frames[frame].transpose() * through);
  double energy = 0.0, unused = 0.0;
  Eigen::VectorXd force, cpuForce;
  bool admissible = true;
  ASSERT_TRUE(forces->evaluate(inverted, energy, force, admissible));
  EXPECT_EQ(admissible, c.reference(inverted, unused, cpuForce));
  EXPECT_FALSE(admissible);
  // A state of the wrong size is an error, not a crash.
  EXPECT_FALSE(forces->evaluate(Eigen::VectorXd::Zero(5), energy, force, admissible));
}

// The Laplacian of a g x g x g grid plus a multiple of the identity (upper triangle): a factor
// with a real supernodal tree.
SparseMatrix GridMatrix(int g) {
  std::vector<Eigen::Triplet<double>> t;
  auto id = [g](int i, int j, int k) { return i + g * (j + g * k); };
  for (int k = 0; k < g; ++k)
    for (int j = 0; j < g; ++j)
      for (int i = 0; i < g; ++i) {
        const int p = id(i, j, k);
        t.emplace_back(p, p, 6.1);
        if (i + 1 < g)
          t.emplace_back(p, id(i + 1, j, k), -1.0);
        if (j + 1 < g)
          t.emplace_back(p, id(i, j + 1, k), -1.0);
        if (k + 1 < g)
          t.emplace_back(p, id(i, j, k + 1), -1.0);
      }
  SparseMatrix upper(g * g * g, g * g * g);
  upper.setFromTriplets(t.begin(), t.end());
  return upper;
}

TEST(CudaLargeDeformation, SubstitutionAndProductMatchTheCpu) {
  REQUIRE_GPU_OR_SKIP();
  auto backend = Gpu();
  ASSERT_TRUE(backend);
  const SparseMatrix upper = GridMatrix(24);
  CholmodFactor factor;
  ASSERT_TRUE(factor.analyze(upper));
  ASSERT_TRUE(factor.factorize(upper));
  SinglePrecisionFactor single;
  ASSERT_TRUE(single.assign(factor));
  std::unique_ptr<FactorOnDevice> device;
  const Status made = backend->makeFactorOnDevice(single, upper, device);
  ASSERT_TRUE(made) << made.message;
  cuda::detail::SweepShape shape;
  ASSERT_TRUE(cuda::detail::ShapeOfFactorOnDevice(*device, shape));
  EXPECT_GT(shape.levels, 3);
  EXPECT_LT(shape.levels, shape.supernodes); // levels group independent supernodes
  EXPECT_GT(shape.maxRows, 32); // a small supernode of more than one panel of 32 columns
  EXPECT_GT(shape.large, 0);    // and large ones, done with cuBLAS
  EXPECT_LT(shape.large, shape.supernodes);
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const SparseMatrix full = upper.selfadjointView<Eigen::Upper>();
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd b(upper.rows());
    for (Eigen::Index i = 0; i < b.size(); ++i)
      b[i] = normal(rng) * (trial == 2 ? 1e-30 : 1.0);
    Eigen::VectorXd x;
    ASSERT_TRUE(device->solve(b, x));
    // Single precision: the residual of the solution to about 1e-6 of b.
    EXPECT_LT((full * x - b).norm(), 1e-5 * b.norm()) << trial;
    Eigen::MatrixXd exact;
    ASSERT_TRUE(factor.solve(b, exact));
    EXPECT_LT((x - exact.col(0)).norm(), 1e-5 * exact.norm()) << trial;
    Eigen::VectorXd product;
    ASSERT_TRUE(device->multiply(b, product));
    const Eigen::VectorXd expected = full * b;
    EXPECT_LE((product - expected).cwiseAbs().maxCoeff(), 1e-13 * expected.cwiseAbs().maxCoeff());
  }
  Eigen::VectorXd x;
  ASSERT_TRUE(device->solve(Eigen::VectorXd::Zero(upper.rows()), x));
  EXPECT_EQ(x.cwiseAbs().maxCoeff(), 0.0);
  Eigen::VectorXd bad = Eigen::VectorXd::Ones(upper.rows());
  bad[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(device->solve(bad, x));
  bad[3] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(device->solve(bad, x));
  EXPECT_FALSE(device->solve(Eigen::VectorXd::Ones(4), x));
  EXPECT_FALSE(device->multiply(Eigen::VectorXd::Ones(4), x));
  // A factor that is only symbolic has no single-precision copy (assign fails and leaves it
  // empty), and an empty copy is refused.
  CholmodFactor symbolic;
  ASSERT_TRUE(symbolic.analyze(upper));
  SinglePrecisionFactor empty;
  EXPECT_FALSE(empty.assign(symbolic));
  std::unique_ptr<FactorOnDevice> none;
  EXPECT_FALSE(backend->makeFactorOnDevice(empty, upper, none));
  EXPECT_FALSE(none);
}

TEST(CudaLargeDeformation, SolvesAndDragsAsTheCpu) {
  // The shell's 5 mm ROI push, some cells small-strain (as LipSeal's bridges), then a drag of
  // four 0.5 mm steps: with the CUDA backend every step runs on the GPU and the results equal the
  // CPU backend's and Newton's to the solvers' agreement (1e-8), and a dragged state equals the
  // cold solve of the same move.
  REQUIRE_GPU_OR_SKIP();
  auto backend = Gpu();
  ASSERT_TRUE(backend);
  PrecomputeRequest cpuRequest = testing::ShellRequest(6, 3);
  cpuRequest.materials.smallStrain.assign(static_cast<size_t>(cpuRequest.mesh.numTets()), 0);
  for (size_t e = 0; e < cpuRequest.materials.smallStrain.size(); e += 7)
    cpuRequest.materials.smallStrain[e] = 1;
  PrecomputeRequest gpuRequest = cpuRequest;
  gpuRequest.options.backend = backend;
  auto gpu = Precomputed(gpuRequest), cpu = Precomputed(cpuRequest), cold = Precomputed(gpuRequest);
  ASSERT_TRUE(gpu && cpu && cold);
  LargeDeformationState state;
  for (int step = 0; step <= 4; ++step) {
    SolveInput input;
    input.movableDisplacement = testing::SmoothRoiField(cpuRequest, 2.5 + 0.25 * step);
    input.recoverInterior = true;
    SolveResult onGpu, onCpu, coldResult;
    PrecomputedLargeDeformationReport gpuReport, cpuReport, coldReport;
    LargeDeformationState next;
    const Status solved = SolvePrecomputedLargeDeformation(*gpu, input, step ? &state : nullptr,
                                                           onGpu, gpuReport, &next);
    ASSERT_TRUE(solved) << "step " << step << ": " << solved.message;
    EXPECT_FALSE(gpuReport.fellBack) << gpuReport.fallbackReason;
    EXPECT_EQ(gpuReport.deviceNote, "");
    EXPECT_EQ(gpuReport.device, backend->name());
    EXPECT_EQ(onGpu.backend, backend->name());
    EXPECT_GT(gpuReport.deviceEvaluations, 0);
    EXPECT_EQ(gpuReport.deviceEvaluations, gpuReport.evaluations);
    EXPECT_EQ(gpuReport.deviceSubstitutions, gpuReport.factorSolves);
    EXPECT_LT(onGpu.relativeResidual, 1e-9);
    EXPECT_EQ(gpuReport.warmStarted, step > 0);
    state = next;
    WaitForRefactorization(*gpu);
    const Status onCpuSolved =
        SolvePrecomputedLargeDeformation(*cpu, input, nullptr, onCpu, cpuReport);
    ASSERT_TRUE(onCpuSolved) << "step " << step << ": " << onCpuSolved.message;
    EXPECT_EQ(cpuReport.device, "CPU");
    EXPECT_EQ(cpuReport.deviceEvaluations, 0);
    EXPECT_LT(RelativeMaxNodeDifference(onGpu.allDisplacement, onCpu.allDisplacement), 1e-8)
        << step;
    EXPECT_NEAR(gpuReport.largestGreenStrain, cpuReport.largestGreenStrain,
                1e-8 * cpuReport.largestGreenStrain);
    EXPECT_NEAR(gpuReport.smallestVolumeRatio, cpuReport.smallestVolumeRatio, 1e-8);
    ASSERT_TRUE(SolvePrecomputedLargeDeformation(*cold, input, nullptr, coldResult, coldReport));
    EXPECT_LT(RelativeMaxNodeDifference(onGpu.allDisplacement, coldResult.allDisplacement), 1e-8)
        << step;
    if (step == 0) {
      LargeDeformationOptions newtonOptions;
      SolveResult newton;
      LargeDeformationReport newtonReport;
      ASSERT_TRUE(SolveLargeDeformation(cpuRequest, input, newtonOptions, newton, newtonReport));
      EXPECT_LT(RelativeMaxNodeDifference(onGpu.allDisplacement, newton.allDisplacement), 1e-8);
      EXPECT_GT(gpuReport.largestGreenStrain, 0.1) << "a large move";
    }
  }
}

TEST(CudaLargeDeformation, LiftOffOnTheGpu) {
  // The sliding shell pushed 10 mm with lift-off: the contact's active set changes during the
  // solve; the GPU's answer is the CPU's.
  REQUIRE_GPU_OR_SKIP();
  auto backend = Gpu();
  ASSERT_TRUE(backend);
  RowVectors3d moves;
  PrecomputeRequest cpuRequest = testing::SlidingShellRequest(10.0, moves);
  PrecomputeRequest gpuRequest = cpuRequest;
  gpuRequest.options.backend = backend;
  PrecomputedLargeDeformationOptions options;
  options.slidingLiftOff = true;
  auto gpu = Precomputed(gpuRequest, options), cpu = Precomputed(cpuRequest, options);
  ASSERT_TRUE(gpu && cpu);
  SolveInput input;
  input.movableDisplacement = moves;
  input.recoverInterior = true;
  SolveResult onGpu, onCpu;
  PrecomputedLargeDeformationReport gpuReport, cpuReport;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*gpu, input, nullptr, onGpu, gpuReport));
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*cpu, input, nullptr, onCpu, cpuReport));
  EXPECT_FALSE(gpuReport.fellBack) << gpuReport.fallbackReason;
  EXPECT_EQ(gpuReport.device, backend->name()) << gpuReport.deviceNote;
  EXPECT_EQ(gpuReport.liftedNodes, cpuReport.liftedNodes);
  EXPECT_LT(RelativeMaxNodeDifference(onGpu.allDisplacement, onCpu.allDisplacement), 1e-8);
}

} // namespace
} // namespace faceplan
