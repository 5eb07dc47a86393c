// SPDX-License-Identifier: BSD-3-Clause
// Every extra solve path of the report agrees with Core's double-precision reference within the
// tolerance it states, on generated shells (no hand-typed meshes).
#include "Common/RelativeDifference.h"
#include "Comparison/ConjugateGradientSolve.h"
#include "Comparison/FreeSystem.h"
#include "Comparison/MassSpringSolve.h"
#include "Comparison/ReverseCuthillMcKee.h"
#include "Comparison/SinglePrecisionCholesky.h"
#include "Comparison/TraditionalBandSolve.h"
#include "CondensedFEM/CondensedFEM.h"
#include "Support/AnalyticHollowSphere.h"
#include "Support/ShellMeshGenerator.h"

#include <gtest/gtest.h>
#include <numeric>
#include <random>

using namespace faceplan;

namespace {

struct Scene {
  PrecomputeRequest request;
  RowVectors3d edit;
};

// Face-like shell (mm, soft tissue): inner surface on bone, a polar ROI cap moved smoothly.
Scene FaceShell(int subdivisions = 5, int layers = 2) {
  const FaceLikeScene f = MakeFaceLikeScene(subdivisions, layers, 0.15);
  Scene s;
  s.request.mesh = f.shell.mesh;
  s.request.materials = Materials::Uniform(3.0e3, 0.45);
  s.request.sets = {f.constrained, f.movable, f.kept};
  s.edit.resize(static_cast<Eigen::Index>(f.movable.size()), 3);
  for (size_t k = 0; k < f.movable.size(); ++k) {
    const Eigen::RowVector3d p = s.request.mesh.points.row(f.movable[k]);
    s.edit.row(k) << 1.5 * std::sin(0.05 * p(0)), -std::cos(0.04 * p(1)),
        2.0 + 0.5 * std::sin(0.03 * (p(0) + p(1)));
  }
  return s;
}

RowVectors3d Reference(const Scene& s) {
  SolveInput input;
  input.movableDisplacement = s.edit;
  SolveResult result;
  EXPECT_TRUE(SolveFullReference(s.request, input, result).ok);
  return result.keptDisplacement;
}

struct Prepared {
  FreeSystem system;
  Eigen::VectorXd roi, rhs;
};
void Prepare(const Scene& s, Prepared& p) {
  ASSERT_TRUE(BuildFreeSystem(s.request, p.system).ok);
  ASSERT_TRUE(RoiVector(p.system, s.edit, p.roi).ok);
  p.rhs = FreeRightHandSide(p.system, p.roi);
}

} // namespace

TEST(SolvePaths, FreeSystemMatchesReferenceWithCholmod) {
  const Scene s = FaceShell();
  Prepared p;
  Prepare(s, p);
  CholmodFactor factor;
  ASSERT_TRUE(factor.analyze(p.system.kff).ok);
  ASSERT_TRUE(factor.factorize(p.system.kff).ok);
  Eigen::MatrixXd x;
  ASSERT_TRUE(factor.solve(p.rhs, x).ok);
  EXPECT_LT(RelativeMaxNodeDifference(KeptDisplacement(p.system, x.col(0), p.roi), Reference(s)),
            1e-10);
}

TEST(SolvePaths, ConjugateGradientsAtTightToleranceMatchReference) {
  const Scene s = FaceShell();
  const RowVectors3d reference = Reference(s);
  Prepared p;
  Prepare(s, p);
  for (CGPreconditioner pre : {CGPreconditioner::IncompleteCholesky, CGPreconditioner::Jacobi}) {
    ConjugateGradientSolver cg;
    CGOptions options;
    options.preconditioner = pre;
    ASSERT_TRUE(cg.setup(p.system, options).ok);
    Eigen::VectorXd x;
    CGReport report;
    ASSERT_TRUE(cg.solve(p.rhs, 1e-10, nullptr, x, report).ok);
    EXPECT_TRUE(report.converged) << CGPreconditionerName(pre);
    EXPECT_LT(report.relativeResidual, 1e-9) << CGPreconditionerName(pre);
    EXPECT_LT(RelativeMaxNodeDifference(KeptDisplacement(p.system, x, p.roi), reference), 1e-8)
        << CGPreconditionerName(pre);
  }
}

TEST(SolvePaths, ConjugateGradientErrorFollowsTolerance) {
  const Scene s = FaceShell();
  const RowVectors3d reference = Reference(s);
  Prepared p;
  Prepare(s, p);
  ConjugateGradientSolver cg;
  ASSERT_TRUE(cg.setup(p.system, {}).ok);
  double previous = 1e300;
  int previousIterations = -1;
  for (double tolerance : {1e-2, 1e-4, 1e-6, 1e-8}) {
    Eigen::VectorXd x;
    CGReport report;
    ASSERT_TRUE(cg.solve(p.rhs, tolerance, nullptr, x, report).ok);
    const double error = RelativeMaxNodeDifference(KeptDisplacement(p.system, x, p.roi), reference);
    EXPECT_LE(report.relativeResidual, 2.0 * tolerance);
    EXPECT_LT(error, previous * 1.01) << tolerance;
    EXPECT_GE(report.iterations, previousIterations);
    previous = error;
    previousIterations = report.iterations;
  }
}

TEST(SolvePaths, WarmStartNeedsFewerIterations) {
  const Scene s = FaceShell();
  Prepared p;
  Prepare(s, p);
  ConjugateGradientSolver cg;
  ASSERT_TRUE(cg.setup(p.system, {}).ok);
  Eigen::VectorXd previous, x;
  CGReport cold, warm;
  ASSERT_TRUE(cg.solve(0.95 * p.rhs, 1e-8, nullptr, previous, cold).ok); // the previous drag step
  ASSERT_TRUE(cg.solve(p.rhs, 1e-8, nullptr, x, cold).ok);
  ASSERT_TRUE(cg.solve(p.rhs, 1e-8, &previous, x, warm).ok);
  EXPECT_LT(warm.iterations, cold.iterations);
  EXPECT_LT(warm.relativeResidual, 1e-7);
}

TEST(SolvePaths, SinglePrecisionWithinItsTolerance) {
  const Scene s = FaceShell();
  const RowVectors3d reference = Reference(s);
  Prepared p;
  Prepare(s, p);
  SinglePrecisionCholesky direct;
  ASSERT_TRUE(direct.factorize(p.system).ok);
  Eigen::VectorXd x;
  SinglePrecisionReport report;
  ASSERT_TRUE(direct.solve(p.rhs, 0, x, report).ok);
  const double plain = RelativeMaxNodeDifference(KeptDisplacement(p.system, x, p.roi), reference);
  EXPECT_LT(plain, 1e-4);
  EXPECT_GT(plain, 1e-12); // it really is single precision
  ASSERT_TRUE(direct.solve(p.rhs, 3, x, report).ok);
  EXPECT_LT(RelativeMaxNodeDifference(KeptDisplacement(p.system, x, p.roi), reference), 1e-9);

  ConjugateGradientSolver cg;
  CGOptions options;
  options.precision = CGPrecision::Single;
  ASSERT_TRUE(cg.setup(p.system, options).ok);
  CGReport cgReport;
  ASSERT_TRUE(cg.solve(p.rhs, 1e-6, nullptr, x, cgReport).ok);
  EXPECT_LT(RelativeMaxNodeDifference(KeptDisplacement(p.system, x, p.roi), reference), 1e-4);
}

TEST(SolvePaths, TraditionalBandCholeskyMatchesReference) {
  std::string why;
  if (!BandLapackAvailable(&why))
    GTEST_SKIP() << why;
  const Scene s = FaceShell();
  TraditionalBandResult band;
  const Status status = SolveTraditionalBand(s.request, s.edit, band);
  ASSERT_TRUE(status.ok) << status.message;
  EXPECT_LT(RelativeMaxNodeDifference(band.keptDisplacement, Reference(s)), 1e-10);
  EXPECT_LT(band.relativeResidual, 1e-12);
  EXPECT_LE(band.semiBandwidth, band.semiBandwidthBefore);
  EXPECT_GT(band.factorizationMs, 0.0);
}

TEST(SolvePaths, ReverseCuthillMcKeeShrinksBandwidthOfShuffledMesh) {
  Scene s = FaceShell(6, 3);
  // Shuffle the node numbering so the natural order is bad.
  const Eigen::Index n = s.request.mesh.numPoints();
  std::vector<int> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(7));
  std::vector<std::vector<int>> neighbours(n);
  for (Eigen::Index e = 0; e < s.request.mesh.numTets(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (a != b)
          neighbours[perm[s.request.mesh.tets(e, a)]].push_back(perm[s.request.mesh.tets(e, b)]);
  std::vector<int> start(n + 1, 0), adjacent;
  for (Eigen::Index v = 0; v < n; ++v) {
    auto& l = neighbours[v];
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    start[v + 1] = start[v] + static_cast<int>(l.size());
    adjacent.insert(adjacent.end(), l.begin(), l.end());
  }
  std::vector<int> natural(n);
  std::iota(natural.begin(), natural.end(), 0);
  const std::vector<int> order = ReverseCuthillMcKee(start, adjacent);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, natural); // a permutation
  EXPECT_LT(GraphBandwidth(start, adjacent, order) * 5, GraphBandwidth(start, adjacent, natural));
}

TEST(SolvePaths, MassSpringRunsAndDiffersFromFEM) {
  const Scene s = FaceShell();
  const RowVectors3d reference = Reference(s);
  MassSpringModel springs;
  ASSERT_TRUE(springs.build(s.request).ok);
  EXPECT_GT(springs.springs(), s.request.mesh.numTets());
  RowVectors3d kept, all;
  ASSERT_TRUE(springs.solve(s.edit, kept, &all).ok);
  ASSERT_TRUE(kept.allFinite());
  EXPECT_GT(kept.rowwise().norm().maxCoeff(), 0.0);
  const double difference = RelativeMaxNodeDifference(kept, reference);
  EXPECT_GT(difference, 1e-3); // a different model, not a different solver
  EXPECT_LT(difference, 10.0); // but the same problem, same boundary conditions
  for (size_t k = 0; k < s.request.sets.movable.size(); ++k) // prescribed nodes are exact
    EXPECT_LT((all.row(s.request.sets.movable[k]) - s.edit.row(k)).norm(), 1e-12);
}

TEST(SolvePaths, HollowSphereCGErrorIsDiscretisationError) {
  HollowSphere exact;
  const ShellMesh shell = MakeSphericalShell(6, 2, exact.a, exact.b);
  PrecomputeRequest r;
  r.mesh = shell.mesh;
  r.materials = Materials::Uniform(exact.E, exact.nu);
  r.sets = {shell.innerNodes, shell.innerNodes, shell.outerNodes};
  RowVectors3d edit(static_cast<Eigen::Index>(shell.innerNodes.size()), 3);
  for (size_t k = 0; k < shell.innerNodes.size(); ++k)
    edit.row(k) =
        exact.displacement(shell.mesh.points.row(shell.innerNodes[k]).transpose()).transpose();
  FreeSystem system;
  ASSERT_TRUE(BuildFreeSystem(r, system).ok);
  Eigen::VectorXd roi, x;
  ASSERT_TRUE(RoiVector(system, edit, roi).ok);
  ConjugateGradientSolver cg;
  ASSERT_TRUE(cg.setup(system, {}).ok);
  CGReport report;
  ASSERT_TRUE(cg.solve(FreeRightHandSide(system, roi), 1e-10, nullptr, x, report).ok);
  CholmodFactor factor;
  ASSERT_TRUE(factor.analyze(system.kff).ok);
  ASSERT_TRUE(factor.factorize(system.kff).ok);
  Eigen::MatrixXd direct;
  ASSERT_TRUE(factor.solve(FreeRightHandSide(system, roi), direct).ok);
  double norm;
  const double error =
      HollowSphereL2Error(r.mesh, AllDisplacement(system, x, roi), exact, norm) / norm;
  const double directError =
      HollowSphereL2Error(r.mesh, AllDisplacement(system, direct.col(0), roi), exact, norm) / norm;
  EXPECT_LT(error, 0.2);
  EXPECT_NEAR(error, directError,
              1e-6 * directError); // solver error far below discretisation error
}

TEST(SolvePaths, ErrorsComeBackAsStatus) {
  const Scene s = FaceShell(3, 1);
  Prepared p;
  Prepare(s, p);
  ConjugateGradientSolver cg;
  Eigen::VectorXd x;
  CGReport report;
  EXPECT_FALSE(cg.solve(p.rhs, 1e-6, nullptr, x, report).ok); // before setup
  ASSERT_TRUE(cg.setup(p.system, {}).ok);
  EXPECT_FALSE(cg.solve(Eigen::VectorXd::Ones(3), 1e-6, nullptr, x, report).ok);
  EXPECT_FALSE(cg.solve(p.rhs, 0.0, nullptr, x, report).ok);
  SinglePrecisionCholesky direct;
  SinglePrecisionReport sr;
  EXPECT_FALSE(direct.solve(p.rhs, 0, x, sr).ok);
  MassSpringModel springs;
  RowVectors3d kept;
  EXPECT_FALSE(springs.solve(s.edit, kept).ok);
  TraditionalBandResult band;
  EXPECT_FALSE(SolveTraditionalBand(s.request, RowVectors3d::Zero(1, 3), band).ok);
  PrecomputeRequest bad = s.request;
  bad.sets.constrained.clear();
  bad.sets.movable.clear();
  FreeSystem system;
  EXPECT_FALSE(BuildFreeSystem(bad, system).ok);
  Eigen::VectorXd roi;
  EXPECT_FALSE(RoiVector(p.system, RowVectors3d::Zero(1, 3), roi).ok);
}
