// SPDX-License-Identifier: BSD-3-Clause
// SparseSolver/MultifrontalCholesky: the multifrontal factor in CHOLMOD's layout must be CHOLMOD's
// factor up to round-off (a wide supernode's too), the same bit for bit from run to run whatever
// the thread schedule, and refuse a matrix that is not positive definite (CholmodFactor then names
// CHOLMOD's first failing column, as before); on a background thread the top's BLAS runs on one
// thread.
#include "Common/BlasThreads.h"
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedSystem.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/MultifrontalCholesky.h"
#include "SparseSolver/MultifrontalWorkspace.h"
#include "SparseSolver/SymbolicAnalysis.h"
#include "Support/FEMTestScenes.h"

#include <cholmod.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

std::shared_ptr<const CondensedSystem> ShellSystem() {
  std::shared_ptr<const CondensedSystem> system;
  const Status precomputed = Precompute(ShellRequest(10, 4), system);
  EXPECT_TRUE(precomputed.ok && system) << precomputed.message;
  return system;
}

// A supernodal analysis of `upper` in METIS's order with the ROI-coupled nodes last (as the
// precompute makes it), relaxed supernodes as CholmodFactor sets them for the CPU or the GPU.
cholmod_factor* Analysed(const CondensedSystem& system, const SparseMatrix& upper,
                         cholmod_common& common,
                         SupernodeRelaxation relaxation = SupernodeRelaxation::Cholmod) {
  common.supernodal = CHOLMOD_SUPERNODAL;
  ApplySupernodeRelaxation(common, relaxation);
  FillReducingOrdering ordering;
  EXPECT_TRUE(OrderNodesWithTrailing(
                  upper, 3, NodesCoupledTo(system.kfr, system.layout.freeNodes(), 3), ordering)
                  .ok);
  return AnalyzeInGivenOrder(upper, ordering.permutation, common);
}

std::vector<double> Values(const cholmod_factor* L) {
  const double* x = static_cast<const double*>(L->x);
  return std::vector<double>(x, x + L->xsize);
}

void ExpectCholmodsFactor(SupernodeRelaxation relaxation) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  QuietCholmodCommon mineQuiet, theirsQuiet;
  cholmod_factor* mine = Analysed(*system, system->kff, mineQuiet.common, relaxation);
  cholmod_factor* theirs = Analysed(*system, system->kff, theirsQuiet.common, relaxation);
  ASSERT_TRUE(mine && theirs);
  ASSERT_GT(mine->nsuper, 20u); // a tree with subtrees to run in parallel
  MultifrontalReport report;
  ASSERT_TRUE(MultifrontalFactorize(system->kff, mine, &mineQuiet.common, 4, &report).ok);
  EXPECT_EQ(report.supernodes, static_cast<int>(mine->nsuper));
  EXPECT_GT(report.topSupernodes, 0);
  EXPECT_LT(report.topSupernodes, report.supernodes);
  cholmod_sparse view = ViewUpper(system->kff);
  ASSERT_TRUE(cholmod_factorize(&view, theirs, &theirsQuiet.common));
  ASSERT_EQ(theirs->minor, theirs->n);
  EXPECT_EQ(mine->minor, mine->n);
  EXPECT_TRUE(mine->is_ll && mine->is_super && mine->xtype == CHOLMOD_REAL);
  const std::vector<double> a = Values(mine), b = Values(theirs);
  ASSERT_EQ(a.size(), b.size());
  double largest = 0.0, difference = 0.0;
  for (size_t k = 0; k < a.size(); ++k) {
    largest = std::max(largest, std::abs(b[k]));
    difference = std::max(difference, std::abs(a[k] - b[k]));
  }
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(difference, 1e-12 * largest);
  cholmod_free_factor(&mine, &mineQuiet.common);
  cholmod_free_factor(&theirs, &theirsQuiet.common);
}

TEST(MultifrontalCholesky, IsCholmodsFactorUpToRoundOff) {
  ExpectCholmodsFactor(SupernodeRelaxation::Cholmod);
  ExpectCholmodsFactor(SupernodeRelaxation::Coarse);
}

// Subtrees run on whichever thread is free, but each supernode adds its children in a fixed
// order: two runs with the same thread count give the same bits (the top's threaded BLAS gets the
// same count both times).
TEST(MultifrontalCholesky, SameBitsOnEveryRun) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  QuietCholmodCommon quiet;
  cholmod_factor* L = Analysed(*system, system->kff, quiet.common);
  ASSERT_TRUE(L);
  ASSERT_TRUE(MultifrontalFactorize(system->kff, L, &quiet.common, 4).ok);
  const std::vector<double> first = Values(L);
  for (int run = 0; run < 3; ++run) {
    ASSERT_TRUE(MultifrontalFactorize(system->kff, L, &quiet.common, 4).ok);
    EXPECT_EQ(Values(L), first) << "run " << run;
  }
  cholmod_free_factor(&L, &quiet.common);
}

// The top's threaded BLAS asks for the factorization's threads (at most 8), but for one thread on
// a thread marked as background work: OpenBLAS's threads would otherwise spin beside the edit the
// user waits for. The factor is the same either way, up to the BLAS's round-off.
TEST(MultifrontalCholesky, ABackgroundThreadsTopRunsItsBlasOnOneThread) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  auto factorOn = [&](bool background, MultifrontalReport& report, std::vector<double>& values) {
    std::thread([&] {
      if (background)
        MarkThreadAsBackground();
      QuietCholmodCommon quiet;
      cholmod_factor* L = Analysed(*system, system->kff, quiet.common);
      ASSERT_TRUE(L);
      ASSERT_TRUE(MultifrontalFactorize(system->kff, L, &quiet.common, 4, &report).ok);
      values = Values(L);
      cholmod_free_factor(&L, &quiet.common);
    }).join();
  };
  MultifrontalReport foreground, background;
  std::vector<double> a, b;
  factorOn(false, foreground, a);
  factorOn(true, background, b);
  ASSERT_GT(foreground.topSupernodes, 0);
  EXPECT_EQ(foreground.topBlasThreads, 4);
  EXPECT_EQ(background.topBlasThreads, 1);
  EXPECT_FALSE(ThreadIsBackground()); // the mark stays with its thread
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LT(RelativeMaxDifference(b.data(), a.data(), a.size()), 1e-12);
}

// Bytes of every supernode's update matrix in double precision at once.
double UpdateBytes(const cholmod_factor& L) {
  double bytes = 0.0;
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  for (size_t t = 0; t < L.nsuper; ++t) {
    const double off = (pi[t + 1] - pi[t]) - (super[t + 1] - super[t]);
    bytes += off * off * sizeof(double);
  }
  return bytes;
}

// A workspace keeps the plan and the update buffers from one factorization to the next. The factor
// is the same bits as without it; the plan is reused for the same pattern only; and what it keeps
// stays within one factorization's update matrices, however many factorizations it serves, and
// shrinks to a smaller matrix's.
TEST(MultifrontalCholesky, AWorkspaceGivesTheSameFactor) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  QuietCholmodCommon quiet;
  cholmod_factor* L = Analysed(*system, system->kff, quiet.common);
  ASSERT_TRUE(L);
  const double updateBytes = UpdateBytes(*L);
  // Another pattern: an off-diagonal entry v at (i, j) (and any stored zero) fewer, with |v| added
  // to both diagonals so that the matrix stays positive definite (the change is
  // |v| (e_i - sign(v) e_j)(e_i - sign(v) e_j)^T).
  SparseMatrix pruned = system->kff;
  const int j = static_cast<int>(pruned.cols()) / 2;
  for (int q = pruned.outerIndexPtr()[j]; q < pruned.outerIndexPtr()[j + 1]; ++q)
    if (const int i = pruned.innerIndexPtr()[q]; i != j && pruned.valuePtr()[q] != 0.0) {
      const double v = std::abs(pruned.valuePtr()[q]);
      pruned.valuePtr()[q] = 0.0;
      pruned.coeffRef(i, i) += v;
      pruned.coeffRef(j, j) += v;
      break;
    }
  pruned.prune(0.0, 0.0);
  ASSERT_LT(pruned.nonZeros(), system->kff.nonZeros());
  const SparseMatrix scaled = 2.0 * system->kff;
  MultifrontalWorkspace workspace;
  int reused = 0;
  const std::vector<const SparseMatrix*> matrices = {&system->kff, &scaled, &system->kff, &pruned,
                                                     &scaled};
  for (const SparseMatrix* m : matrices) {
    ASSERT_TRUE(MultifrontalFactorize(*m, L, &quiet.common, 4).ok);
    const std::vector<double> without = Values(L);
    ASSERT_TRUE(MultifrontalFactorize(*m, L, &quiet.common, 4, nullptr, &workspace).ok);
    EXPECT_EQ(Values(L), without);
    EXPECT_GT(workspace.keptBytes(), 0.0);
    EXPECT_LE(workspace.keptBytes(), updateBytes);
    reused = workspace.plansReused();
  }
  EXPECT_EQ(reused, 2) << "the same pattern after the first and the third; then made again twice";
  cholmod_free_factor(&L, &quiet.common);

  std::shared_ptr<const CondensedSystem> small;
  ASSERT_TRUE(Precompute(ShellRequest(4, 2), small).ok);
  cholmod_factor* smallL = Analysed(*small, small->kff, quiet.common);
  ASSERT_TRUE(smallL);
  ASSERT_LT(UpdateBytes(*smallL), 0.1 * updateBytes);
  ASSERT_TRUE(MultifrontalFactorize(small->kff, smallL, &quiet.common, 4, nullptr, &workspace).ok);
  EXPECT_LE(workspace.keptBytes(), UpdateBytes(*smallL));
  cholmod_free_factor(&smallL, &quiet.common);
}

TEST(MultifrontalCholesky, RefusesAMatrixThatIsNotPositiveDefinite) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  SparseMatrix indefinite = system->kff;
  const int column = static_cast<int>(indefinite.cols()) / 2;
  indefinite.coeffRef(column, column) = -1.0;
  QuietCholmodCommon quiet;
  cholmod_factor* L = Analysed(*system, indefinite, quiet.common);
  ASSERT_TRUE(L);
  const Status s = MultifrontalFactorize(indefinite, L, &quiet.common, 4);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("not positive definite"), std::string::npos) << s.message;
  EXPECT_LT(L->minor, L->n);
  cholmod_free_factor(&L, &quiet.common);

  // Through CholmodFactor the message names CHOLMOD's first failing column, as with
  // FACEPLAN_FACTORIZATION=cholmod.
  std::string messages[2];
  for (int m = 0; m < 2; ++m) {
    if (m == 1)
      setenv("FACEPLAN_FACTORIZATION", "cholmod", 1);
    CholmodFactor factor;
    ASSERT_TRUE(factor.analyze(indefinite).ok);
    const Status failed = factor.factorize(indefinite);
    EXPECT_FALSE(failed.ok);
    EXPECT_FALSE(factor.isFactorized());
    messages[m] = failed.message;
  }
  unsetenv("FACEPLAN_FACTORIZATION");
  EXPECT_EQ(messages[0], messages[1]);
  EXPECT_NE(messages[0].find("CHOLMOD stopped at column"), std::string::npos) << messages[0];
}

// A dense matrix is one supernode, whose panel (its diagonal block and the rows below) is factored
// by halving its columns down to small leaves: widths that split into uneven halves and leaves
// smaller than the rest. Its factor is CHOLMOD's in double and single precision, and where a pivot
// fails the failing column is named exactly: A = M D M^T with M unit lower triangular and D the
// identity but for -1 at `column`, whose Cholesky pivots are D's.
TEST(MultifrontalCholesky, FactorsAWideSupernodeAndNamesItsFailingColumn) {
  for (const int n : {7, 9, 50, 131}) {
    for (const int column : {-1, 0, n / 2 - 1, n - 1}) { // -1: positive definite
      Eigen::MatrixXd m = Eigen::MatrixXd::Identity(n, n);
      for (int j = 0; j < n; ++j)
        for (int i = j + 1; i < n; ++i)
          m(i, j) = 0.3 * std::sin(1.0 + i * 7 + j * 3);
      Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
      if (column >= 0)
        d[column] = -1.0;
      const Eigen::MatrixXd dense = m * d.asDiagonal() * m.transpose();
      const SparseMatrix upper = dense.triangularView<Eigen::Upper>().toDenseMatrix().sparseView();
      std::vector<int> natural(n);
      for (int k = 0; k < n; ++k)
        natural[k] = k;
      QuietCholmodCommon quiet;
      quiet.common.supernodal = CHOLMOD_SUPERNODAL;
      cholmod_factor* mine = AnalyzeInGivenOrder(upper, natural, quiet.common);
      cholmod_factor* theirs = AnalyzeInGivenOrder(upper, natural, quiet.common);
      ASSERT_TRUE(mine && theirs);
      ASSERT_EQ(mine->nsuper, 1u) << n;
      std::vector<float> single(static_cast<const int*>(mine->px)[1]);
      const Status s = MultifrontalFactorize(upper, mine, &quiet.common, 2);
      const Status f = MultifrontalFactorizeSingle(upper, *mine, single.data(), 2);
      if (column >= 0) {
        const std::string named = "pivot failed at column " + std::to_string(column) + ")";
        EXPECT_FALSE(s.ok);
        EXPECT_EQ(mine->minor, static_cast<size_t>(column)) << n;
        EXPECT_NE(s.message.find(named), std::string::npos) << n << ": " << s.message;
        EXPECT_FALSE(f.ok);
        EXPECT_NE(f.message.find(named), std::string::npos) << n << ": " << f.message;
      } else {
        ASSERT_TRUE(s.ok) << s.message;
        ASSERT_TRUE(f.ok) << f.message;
        cholmod_sparse view = ViewUpper(upper);
        ASSERT_TRUE(cholmod_factorize(&view, theirs, &quiet.common));
        ASSERT_EQ(theirs->minor, theirs->n);
        const std::vector<double> a = Values(mine), b = Values(theirs);
        ASSERT_EQ(a.size(), b.size());
        ASSERT_EQ(single.size(), b.size());
        double largest = 0.0, difference = 0.0, singleDifference = 0.0;
        for (size_t k = 0; k < a.size(); ++k) {
          largest = std::max(largest, std::abs(b[k]));
          difference = std::max(difference, std::abs(a[k] - b[k]));
          singleDifference = std::max(singleDifference, std::abs(single[k] - b[k]));
        }
        EXPECT_LT(difference, 1e-13 * largest) << n;
        EXPECT_LT(singleDifference, 1e-5 * largest) << n;
        // The strictly upper triangle of the diagonal block is zero, as CHOLMOD leaves it.
        for (int j = 1; j < n; ++j)
          for (int i = 0; i < j; ++i)
            ASSERT_EQ(a[static_cast<size_t>(j) * n + i], 0.0) << n << " " << i << " " << j;
      }
      cholmod_free_factor(&mine, &quiet.common);
      cholmod_free_factor(&theirs, &quiet.common);
    }
  }
}

// A factorization that reuses a reference (MultifrontalRefactorizeSingle). With tolerance 0 it is
// the whole factorization bit for bit and factors only the supernodes that a change reaches (the
// changed column's, its ancestors', and the children they need whose updates are not kept);
// changes within the tolerance reuse every supernode and give the reference's factor; a
// reference of another pattern is not reused; a pivot that fails in a supernode factored again
// is an error.
TEST(MultifrontalCholesky, RefactorizationReusesTheSupernodesAChangeDoesNotReach) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  const SparseMatrix& upper = system->kff;
  QuietCholmodCommon quiet;
  cholmod_factor* L = Analysed(*system, upper, quiet.common);
  ASSERT_TRUE(L);
  ASSERT_GT(L->nsuper, 20u);
  const size_t size = static_cast<size_t>(static_cast<const int*>(L->px)[L->nsuper]);
  // The diagonal entry of the column eliminated first, and of the one in the middle.
  auto diagonal = [&](const SparseMatrix& m, size_t position) {
    const int column = static_cast<const int*>(L->Perm)[position];
    for (int q = m.outerIndexPtr()[column]; q < m.outerIndexPtr()[column + 1]; ++q)
      if (m.innerIndexPtr()[q] == column)
        return q;
    return -1;
  };
  MultifrontalReference reference;
  EXPECT_FALSE(reference.made());
  std::vector<float> rest(size), whole(size), reused(size);
  ASSERT_TRUE(
      MultifrontalFactorizeSingle(upper, *L, rest.data(), 2, nullptr, nullptr, &reference).ok);
  ASSERT_TRUE(reference.made());
  EXPECT_GT(reference.keptBytes(), 4.0 * size);

  for (const size_t position : {size_t{0}, static_cast<size_t>(L->n / 2)}) {
    SparseMatrix changed = upper;
    const int q = diagonal(changed, position);
    ASSERT_GE(q, 0);
    changed.valuePtr()[q] *= 1.5; // still positive definite
    MultifrontalReport full, partial;
    ASSERT_TRUE(MultifrontalFactorizeSingle(changed, *L, whole.data(), 2, &full).ok);
    ASSERT_TRUE(
        MultifrontalRefactorizeSingle(changed, *L, reused.data(), 2, reference, 0.0, &partial).ok);
    EXPECT_EQ(reused, whole) << "column position " << position;
    EXPECT_NE(reused, rest);
    EXPECT_EQ(full.supernodesFactored, full.supernodes);
    EXPECT_EQ(full.factoredFlopsShare, 1.0);
    EXPECT_GT(partial.supernodesFactored, 0);
    EXPECT_LT(partial.supernodesFactored, partial.supernodes) << "column position " << position;
    EXPECT_GT(partial.factoredFlopsShare, 0.0);
    EXPECT_LT(partial.factoredFlopsShare, 1.0);
  }

  SparseMatrix scaled = upper;
  for (Eigen::Index k = 0; k < scaled.nonZeros(); ++k)
    scaled.valuePtr()[k] *= 1.0 + 1e-4;
  MultifrontalReport report;
  ASSERT_TRUE(
      MultifrontalRefactorizeSingle(scaled, *L, reused.data(), 2, reference, 1e-3, &report).ok);
  EXPECT_EQ(report.supernodesFactored, 0);
  EXPECT_EQ(reused, rest);
  ASSERT_TRUE(
      MultifrontalRefactorizeSingle(scaled, *L, reused.data(), 2, reference, 1e-5, &report).ok);
  EXPECT_EQ(report.supernodesFactored, report.supernodes);

  SparseMatrix failing = upper;
  failing.valuePtr()[diagonal(failing, L->n / 2)] = -1.0;
  const Status s = MultifrontalRefactorizeSingle(failing, *L, reused.data(), 2, reference, 0.0);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("not positive definite"), std::string::npos) << s.message;

  // A reference made for another matrix's pattern: the whole factorization.
  MultifrontalReference elsewhere;
  {
    const auto bigger = [] {
      std::shared_ptr<const CondensedSystem> made;
      EXPECT_TRUE(Precompute(ShellRequest(12, 4), made).ok);
      return made;
    }();
    ASSERT_TRUE(bigger);
    QuietCholmodCommon otherQuiet;
    cholmod_factor* M = Analysed(*bigger, bigger->kff, otherQuiet.common);
    ASSERT_TRUE(M);
    std::vector<float> values(static_cast<size_t>(static_cast<const int*>(M->px)[M->nsuper]));
    ASSERT_TRUE(
        MultifrontalFactorizeSingle(bigger->kff, *M, values.data(), 2, nullptr, nullptr, &elsewhere)
            .ok);
    cholmod_free_factor(&M, &otherQuiet.common);
  }
  ASSERT_TRUE(
      MultifrontalRefactorizeSingle(upper, *L, reused.data(), 2, elsewhere, 1.0, &report).ok);
  EXPECT_EQ(report.supernodesFactored, report.supernodes);
  EXPECT_EQ(reused, rest);
  cholmod_free_factor(&L, &quiet.common);
}

// The factor CholmodFactor makes multifrontally solves as CHOLMOD's does.
TEST(MultifrontalCholesky, CholmodFactorSolvesWithIt) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(system->kff.rows(), 3);
  Eigen::MatrixXd x[2];
  for (int m = 0; m < 2; ++m) {
    if (m == 1)
      setenv("FACEPLAN_FACTORIZATION", "cholmod", 1);
    CholmodFactor factor;
    ASSERT_TRUE(factor.analyze(system->kff).ok);
    ASSERT_TRUE(factor.factorize(system->kff).ok);
    ASSERT_TRUE(factor.solve(b, x[m]).ok);
  }
  unsetenv("FACEPLAN_FACTORIZATION");
  EXPECT_LT((x[0] - x[1]).norm(), 1e-12 * x[1].norm());
  const Eigen::MatrixXd residual = system->kff.selfadjointView<Eigen::Upper>() * x[0] - b;
  EXPECT_LT(residual.norm(), 1e-12 * b.norm());
}

} // namespace
