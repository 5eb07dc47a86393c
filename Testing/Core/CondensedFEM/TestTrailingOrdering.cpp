// SPDX-License-Identifier: BSD-3-Clause
// The ROI-coupled-last ordering (Core/FillReducingOrdering), the trailing solve it enables
// (CholmodFactor::solveTrailing) and the dense response built from it (Core/TrailingResponse),
// including the choice against the plain ordering and the fallback to refined full solves.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedSystem.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <thread>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

std::shared_ptr<const CondensedSystem> PrecomputeOrFail(const PrecomputeRequest& request) {
  std::shared_ptr<const CondensedSystem> system;
  const Status s = Precompute(request, system);
  EXPECT_TRUE(s.ok) << s.message;
  return system;
}

// A request whose ROI is the whole inner surface: the ROI-coupled nodes are a whole node layer.
PrecomputeRequest WholeSurfaceRoiRequest(int subdivisions, int layers) {
  PrecomputeRequest request = ShellRequest(subdivisions, layers);
  request.sets.movable = request.sets.constrained;
  return request;
}

void ExpectAgreesWithReference(const PrecomputeRequest& request, const CondensedSystem& system) {
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  SolveResult condensed, reference;
  ASSERT_TRUE(Solve(system, input, condensed).ok);
  ASSERT_TRUE(SolveFullReference(request, input, reference).ok);
  EXPECT_LT(RelativeMaxDifference(condensed.keptDisplacement, reference.keptDisplacement), 1e-10);
}

} // namespace

TEST(FillReducingOrdering, PutsMarkedNodesLastAndKeepsNodesTogether) {
  const PrecomputeRequest request = ShellRequest(4, 3);
  const auto system = PrecomputeOrFail(request);
  ASSERT_TRUE(system);
  const int nodes = system->layout.freeNodes(), n = 3 * nodes;
  const std::vector<char> coupled = NodesCoupledTo(system->kfr, nodes, 3);
  int marked = 0;
  for (char c : coupled)
    marked += c;
  ASSERT_GT(marked, 0);
  ASSERT_LT(marked, nodes);

  FillReducingOrdering ordering;
  ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, coupled, ordering).ok);
  ASSERT_EQ(static_cast<int>(ordering.permutation.size()), n);
  EXPECT_EQ(ordering.trailingDofs, 3 * marked);
  std::vector<int> seen(n, 0);
  for (int dof : ordering.permutation) {
    ASSERT_GE(dof, 0);
    ASSERT_LT(dof, n);
    ++seen[dof];
  }
  for (int count : seen)
    EXPECT_EQ(count, 1);           // a permutation
  for (int p = 0; p < n; p += 3) { // each node's three DOFs together, in order
    EXPECT_EQ(ordering.permutation[p] % 3, 0);
    EXPECT_EQ(ordering.permutation[p + 1], ordering.permutation[p] + 1);
    EXPECT_EQ(ordering.permutation[p + 2], ordering.permutation[p] + 2);
    const bool last = p >= n - ordering.trailingDofs;
    EXPECT_EQ(static_cast<bool>(coupled[ordering.permutation[p] / 3]), last) << "position " << p;
  }
}

// The Precompute orders K_FF from the cells' node graph while the assembly runs: the structure,
// the ROI-coupled marks and the ordering it gets that way must be those of the assembled blocks.
TEST(FillReducingOrdering, NodeGraphGivesTheOrderingOfTheAssembledBlock) {
  PrecomputeRequest request = ShellRequest(15, 6);
  request.options.method = SolveMethod::CachedFactor;
  const auto system = PrecomputeOrFail(request);
  ASSERT_TRUE(system);
  EXPECT_TRUE(system->info.orderedBesideAssembly);
  const int freeNodes = system->layout.freeNodes();
  ASSERT_GE(freeNodes, 12000); // large enough for a dissection of many levels
  const NodeNeighbours lower =
      LowerNodeNeighbours(system->cornerMesh.tets.data(), system->cornerMesh.numTets(), 4,
                          system->layout.dofNode, static_cast<int>(system->layout.meshNode.size()));

  SparseMatrix pattern;
  ASSERT_TRUE(UpperPatternOfNodes(lower, freeNodes, true, pattern).ok);
  const SparseMatrix& kff = system->kff;
  ASSERT_EQ(pattern.rows(), kff.rows());
  ASSERT_EQ(pattern.nonZeros(), kff.nonZeros());
  EXPECT_TRUE(std::equal(kff.outerIndexPtr(), kff.outerIndexPtr() + kff.cols() + 1,
                         pattern.outerIndexPtr()));
  EXPECT_TRUE(std::equal(kff.innerIndexPtr(), kff.innerIndexPtr() + kff.nonZeros(),
                         pattern.innerIndexPtr()));

  const std::vector<char> coupled = NodesCoupledToLaterNodes(lower, freeNodes);
  EXPECT_EQ(coupled, NodesCoupledTo(system->kfr, freeNodes, 3));
  for (const std::vector<char>& marks : {coupled, std::vector<char>{}}) {
    FillReducingOrdering fromGraph, fromMatrix;
    ASSERT_TRUE(OrderNodeGraphWithTrailing(lower, freeNodes, 3, marks, fromGraph).ok);
    ASSERT_TRUE(OrderNodesWithTrailing(kff, 3, marks, fromMatrix).ok);
    FillReducingOrdering again;
    ASSERT_TRUE(OrderNodesWithTrailing(kff, 3, marks, again).ok);
    EXPECT_EQ(again.permutation, fromMatrix.permutation) << "matrix twice";
    EXPECT_EQ(fromGraph.permutation, fromMatrix.permutation);
    EXPECT_EQ(fromGraph.trailingDofs, fromMatrix.trailingDofs);
  }
}

// Orderings made at once on several threads (two precomputes, or the precompute's ordering thread
// beside another) are those made alone: METIS keeps its random generator in global state, so
// without the per-thread generator (MetisRandom.h) or MetisMutex concurrent calls draw from it in
// turn and get different orderings. Each ordering also splits its dissection's top into four
// parts ordered on threads (the shell has >= 10,000 free nodes, enough for two levels).
TEST(FillReducingOrdering, OrderingsMadeAtOnceEqualTheOneMadeAlone) {
  const auto system = PrecomputeOrFail(ShellRequest(16, 5));
  ASSERT_TRUE(system);
  const int freeNodes = system->layout.freeNodes();
  const std::vector<char> coupled = NodesCoupledTo(system->kfr, freeNodes, 3);
  constexpr int kLeaves = 4;
  FillReducingOrdering alone;
  ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, coupled, alone, kLeaves).ok);
  EXPECT_GT(alone.leaves, 1);
  constexpr int kThreads = 4;
  std::vector<FillReducingOrdering> atOnce(kThreads);
  std::vector<char> ok(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t]() {
      // Half of them with no marks: different graphs at once, as two different requests.
      const std::vector<char> marks = t % 2 == 0 ? coupled : std::vector<char>{};
      ok[t] = OrderNodesWithTrailing(system->kff, 3, marks, atOnce[t], kLeaves).ok;
    });
  for (std::thread& thread : threads)
    thread.join();
  FillReducingOrdering plain;
  ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, {}, plain, kLeaves).ok);
  for (int t = 0; t < kThreads; ++t) {
    ASSERT_TRUE(ok[t]) << "thread " << t;
    EXPECT_EQ(atOnce[t].permutation, (t % 2 == 0 ? alone : plain).permutation) << "thread " << t;
  }
}

TEST(FillReducingOrdering, RejectsMarksOfTheWrongSize) {
  const auto system = PrecomputeOrFail(ShellRequest(3, 2));
  ASSERT_TRUE(system);
  FillReducingOrdering ordering;
  const Status s = OrderNodesWithTrailing(system->kff, 3, std::vector<char>(5, 1), ordering);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("do not match"), std::string::npos) << s.message;
}

TEST(CholmodFactor, TrailingSolveEqualsFullSolve) {
  const auto system = PrecomputeOrFail(ShellRequest(4, 3));
  ASSERT_TRUE(system);
  const int nodes = system->layout.freeNodes();
  FillReducingOrdering ordering;
  ASSERT_TRUE(
      OrderNodesWithTrailing(system->kff, 3, NodesCoupledTo(system->kfr, nodes, 3), ordering).ok);
  CholmodFactor factor;
  ASSERT_TRUE(factor.analyze(system->kff, &ordering).ok);
  EXPECT_EQ(factor.trailingDofs(), ordering.trailingDofs);
  ASSERT_TRUE(factor.factorize(system->kff).ok);

  const SparseMatrix b = system->kfr.leftCols(std::min<Eigen::Index>(7, system->kfr.cols()));
  Eigen::MatrixXd trailing, full;
  ASSERT_TRUE(factor.solveTrailing(b, trailing).ok);
  ASSERT_TRUE(factor.solve(Eigen::MatrixXd(b), full).ok);
  EXPECT_LT(RelativeMaxDifference(trailing, full), 1e-12);

  // A right-hand side with a non-zero outside the trailing DOFs is refused, not mis-solved.
  SparseMatrix outside(system->kff.rows(), 1);
  outside.insert(ordering.permutation.front(), 0) = 1.0;
  outside.makeCompressed();
  const Status s = factor.solveTrailing(outside, trailing);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("outside the trailing"), std::string::npos) << s.message;
}

TEST(CholmodFactor, WithoutATrailingOrderingTheTrailingSolveIsRefused) {
  const auto system = PrecomputeOrFail(ShellRequest(3, 2));
  ASSERT_TRUE(system);
  CholmodFactor factor;
  ASSERT_TRUE(factor.analyze(system->kff).ok);
  ASSERT_TRUE(factor.factorize(system->kff).ok);
  EXPECT_EQ(factor.trailingDofs(), 0);
  Eigen::MatrixXd x;
  EXPECT_FALSE(factor.solveTrailing(system->kfr, x).ok);
}

TEST(TrailingResponse, SmallRoiUsesTheTrailingBlock) {
  PrecomputeRequest request = ShellRequest(6, 3);
  request.options.method = SolveMethod::DenseResponse;
  const auto system = PrecomputeOrFail(request);
  ASSERT_TRUE(system);
  const SystemInfo info = Describe(*system);
  EXPECT_NE(info.ordering.find("ROI-coupled DOFs last"), std::string::npos) << info.ordering;
  EXPECT_NE(info.responsePath.find("substitutions from the ROI-coupled trailing block"),
            std::string::npos)
      << info.responsePath;
  EXPECT_LE(system->responseResidual, 1e-12);
  ExpectAgreesWithReference(request, *system);
}

// With the ROI on the whole inner surface the ROI-coupled nodes are a whole node layer; as a
// dense trailing block they would cost more than they save, so the plain ordering is kept and the
// forward substitutions run over the coupled DOFs' reach instead.
TEST(TrailingResponse, LargeRoiKeepsThePlainOrdering) {
  PrecomputeRequest request = WholeSurfaceRoiRequest(6, 2);
  request.options.method = SolveMethod::DenseResponse;
  const auto system = PrecomputeOrFail(request);
  ASSERT_TRUE(system);
  const SystemInfo info = Describe(*system);
  EXPECT_EQ(info.ordering.find("ROI-coupled"), std::string::npos) << info.ordering;
  EXPECT_NE(info.responsePath.find("over the ROI-coupled DOFs' reach"), std::string::npos)
      << info.responsePath;
  EXPECT_LE(system->responseResidual, 1e-12);
  ExpectAgreesWithReference(request, *system);
}

// When the probe estimate misses the tolerance the response is redone with full solves, a
// residual per column and refinement (here forced with a tolerance below rounding).
TEST(TrailingResponse, MissedEstimateFallsBackToRefinedFullSolves) {
  PrecomputeRequest request = ShellRequest(5, 2);
  request.options.method = SolveMethod::DenseResponse;
  request.options.residualTolerance = 1e-20;
  request.options.maxRefinementSteps = 1;
  const auto system = PrecomputeOrFail(request);
  ASSERT_TRUE(system);
  const SystemInfo info = Describe(*system);
  EXPECT_NE(info.responsePath.find("full solves with per-column residuals"), std::string::npos)
      << info.responsePath;
  EXPECT_NE(info.responsePath.find("missed"), std::string::npos) << info.responsePath;
  ExpectAgreesWithReference(request, *system);
}

TEST(TrailingResponse, CachedFactorEditsWithLoadsMatchTheReference) {
  PrecomputeRequest request = ShellRequest(5, 3);
  request.options.method = SolveMethod::CachedFactor;
  const auto system = PrecomputeOrFail(request);
  ASSERT_TRUE(system);
  ASSERT_GT(system->factor.trailingDofs(), 0);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  input.gravity = Eigen::Vector3d(0.0, 0.0, -9810.0);
  for (int edit = 0; edit < 2; ++edit) { // the second edit reuses the load's response
    input.movableDisplacement *= 0.5;
    SolveResult condensed, reference;
    ASSERT_TRUE(Solve(*system, input, condensed).ok);
    ASSERT_TRUE(SolveFullReference(request, input, reference).ok);
    EXPECT_LT(condensed.relativeResidual, 1e-12);
    EXPECT_LT(RelativeMaxDifference(condensed.keptDisplacement, reference.keptDisplacement), 1e-10);
  }
}
