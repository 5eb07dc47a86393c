// SPDX-License-Identifier: BSD-3-Clause
// PrunedBackSubstitution and PrunedForwardSubstitution (Core/SparseSolver): the substitutions on
// row-major blocks agree with CHOLMOD's own solve; restricting the backward one to wanted rows
// changes none of their values while it skips supernodes, and the forward one over a right-hand
// side's reach is the whole forward substitution.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedSystem.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "SparseSolver/PrunedBackSubstitution.h"
#include "SparseSolver/PrunedForwardSubstitution.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

struct FactoredShell {
  std::shared_ptr<const CondensedSystem> system;
  CholmodFactor factor;
  FillReducingOrdering ordering;
};

// The shell's K_FF factored with its ROI-coupled DOFs last, as the dense response uses it.
void FactorShell(FactoredShell& out) {
  PrecomputeRequest request = ShellRequest(5, 3);
  ASSERT_TRUE(Precompute(request, out.system).ok);
  const CondensedSystem& sys = *out.system;
  ASSERT_TRUE(OrderNodesWithTrailing(sys.kff, 3, NodesCoupledTo(sys.kfr, sys.layout.freeNodes(), 3),
                                     out.ordering)
                  .ok);
  ASSERT_TRUE(out.factor.analyze(sys.kff, &out.ordering).ok);
  ASSERT_GT(out.factor.trailingDofs(), 0);
  ASSERT_TRUE(out.factor.factorize(sys.kff).ok);
  ASSERT_NE(out.factor.numericFactor(), nullptr);
}

std::vector<double> RandomRows(int n, int columns, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> x(size_t(n) * columns);
  for (double& v : x)
    v = uniform(rng);
  return x;
}

} // namespace

// Forward through the trailing block, then the backward substitution on every row: the same
// solution as CHOLMOD's trailing solve (its own backward substitution).
TEST(PrunedBackSubstitution, AllRowsMatchCholmodsSolve) {
  FactoredShell shell;
  FactorShell(shell);
  const CondensedSystem& sys = *shell.system;
  const int n = static_cast<int>(sys.kff.rows()), t = shell.factor.trailingDofs(), first = n - t;
  const int columns = 5;
  const SparseMatrix b = sys.kfr.leftCols(columns);
  Eigen::MatrixXd cholmod; // in the original DOF order
  ASSERT_TRUE(shell.factor.solveTrailing(b, cholmod).ok);

  // Rows above the trailing block are garbage on entry: they must not be read.
  std::vector<double> x(size_t(n) * columns, std::numeric_limits<double>::quiet_NaN());
  Eigen::MatrixXd tail = Eigen::MatrixXd::Zero(t, columns);
  const std::vector<int>& position = shell.factor.eliminationPosition();
  for (int c = 0; c < columns; ++c)
    for (SparseMatrix::InnerIterator it(b, c); it; ++it)
      tail(position[it.row()] - first, c) = it.value();
  shell.factor.trailingFactorBlock().triangularView<Eigen::Lower>().solveInPlace(tail);
  for (int r = 0; r < t; ++r)
    for (int c = 0; c < columns; ++c)
      x[size_t(first + r) * columns + c] = tail(r, c);

  PrunedBackSubstitution all;
  ASSERT_TRUE(all.prepare(*shell.factor.numericFactor(), {}).ok);
  EXPECT_DOUBLE_EQ(all.flopsPerColumn(), all.fullFlopsPerColumn());
  std::vector<double> scratch;
  all.solve(x.data(), columns, first, scratch);
  Eigen::MatrixXd ours(n, columns);
  for (int dof = 0; dof < n; ++dof)
    for (int c = 0; c < columns; ++c)
      ours(dof, c) = x[size_t(position[dof]) * columns + c];
  ASSERT_TRUE(ours.allFinite());
  EXPECT_LT(RelativeMaxDifference(ours, cholmod), 1e-12);
}

// Restricted to a few rows, the solve visits fewer supernodes and gives exactly the values the
// whole solve gives on those rows (the same operations on every supernode they depend on).
TEST(PrunedBackSubstitution, WantedRowsAreExactAndOtherSupernodesSkipped) {
  FactoredShell shell;
  FactorShell(shell);
  const int n = static_cast<int>(shell.system->kff.rows()), columns = 3;
  PrunedBackSubstitution all, few;
  ASSERT_TRUE(all.prepare(*shell.factor.numericFactor(), {}).ok);
  const std::vector<int> wanted = {0, 1, 2, n / 7}; // early positions: leaves of the tree
  ASSERT_TRUE(few.prepare(*shell.factor.numericFactor(), wanted).ok);
  EXPECT_LT(few.flopsPerColumn(), 0.9 * all.flopsPerColumn());

  const std::vector<double> y = RandomRows(n, columns, 7);
  std::vector<double> whole = y, pruned = y, scratch;
  all.solve(whole.data(), columns, 0, scratch);
  few.solve(pruned.data(), columns, 0, scratch);
  for (int p : wanted)
    for (int c = 0; c < columns; ++c)
      EXPECT_EQ(pruned[size_t(p) * columns + c], whole[size_t(p) * columns + c]) << "row " << p;
}

TEST(PrunedBackSubstitution, RefusesASymbolicFactorAndRowsOutsideIt) {
  FactoredShell shell;
  FactorShell(shell);
  PrunedBackSubstitution solve;
  const int n = static_cast<int>(shell.system->kff.rows());
  Status s = solve.prepare(*shell.factor.numericFactor(), {n});
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("outside the factor"), std::string::npos) << s.message;

  CholmodFactor symbolic;
  ASSERT_TRUE(symbolic.analyze(shell.system->kff, &shell.ordering).ok);
  EXPECT_EQ(symbolic.numericFactor(), nullptr); // nothing to misuse before factorize()
}

// With the plain ordering (no trailing block) the forward substitution runs over the reach of the
// coupled rows; with the backward one after it, the result is CHOLMOD's full solve.
TEST(PrunedForwardSubstitution, ReachThenBackwardMatchesCholmodsSolve) {
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(ShellRequest(5, 3), system).ok);
  const SparseMatrix& kff = system->kff;
  CholmodFactor factor;
  FillReducingOrdering plain;
  ASSERT_TRUE(OrderNodesWithTrailing(kff, 3, {}, plain).ok);
  ASSERT_TRUE(factor.analyze(kff, &plain).ok);
  ASSERT_EQ(factor.trailingDofs(), 0);
  ASSERT_TRUE(factor.factorize(kff).ok);
  const int n = static_cast<int>(kff.rows()), columns = 4;
  const SparseMatrix b = system->kfr.leftCols(columns);
  const std::vector<int>& position = factor.eliminationPosition();
  std::vector<int> nonZero;
  for (int c = 0; c < columns; ++c)
    for (SparseMatrix::InnerIterator it(b, c); it; ++it)
      nonZero.push_back(position[it.row()]);

  PrunedForwardSubstitution forward;
  PrunedBackSubstitution backward;
  ASSERT_TRUE(forward.prepare(*factor.numericFactor(), nonZero).ok);
  ASSERT_TRUE(backward.prepare(*factor.numericFactor(), {}).ok);
  EXPECT_LT(forward.flopsPerColumn(), backward.fullFlopsPerColumn()); // some supernodes skipped

  // Rows outside the reach are garbage on entry: neither substitution may read them as data.
  std::vector<double> x(size_t(n) * columns, std::numeric_limits<double>::quiet_NaN()), scratch;
  forward.clearReach(x.data(), columns);
  for (int c = 0; c < columns; ++c)
    for (SparseMatrix::InnerIterator it(b, c); it; ++it)
      x[size_t(position[it.row()]) * columns + c] = it.value();
  forward.solve(x.data(), columns, scratch);
  backward.solve(x.data(), columns, 0, scratch, &forward.reached());

  Eigen::MatrixXd ours(n, columns), cholmod;
  for (int dof = 0; dof < n; ++dof)
    for (int c = 0; c < columns; ++c)
      ours(dof, c) = x[size_t(position[dof]) * columns + c];
  ASSERT_TRUE(factor.solve(Eigen::MatrixXd(b), cholmod).ok);
  ASSERT_TRUE(ours.allFinite());
  EXPECT_LT(RelativeMaxDifference(ours, cholmod), 1e-12);
}
