// SPDX-License-Identifier: BSD-3-Clause
// SparseSolver/SymbolicAnalysis: the supernodal analysis in a given order, from the node graph when
// the matrix is node-blocked and from a permuted copy otherwise, must be the factor CHOLMOD makes
// from the original matrix with the same ordering (cholmod_analyze_p, CHOLMOD_GIVEN, postordered),
// array for array, with the same nonzero and flop counts; CholmodFactor::analyze uses it.
#include "CondensedFEM/CondensedSystem.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "SparseSolver/SymbolicAnalysis.h"
#include "Support/FEMTestScenes.h"

#include <cholmod.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

std::vector<int> Ints(const void* data, size_t count) {
  const int* begin = static_cast<const int*>(data);
  return std::vector<int>(begin, begin + count);
}

// CholmodFactor's settings (relaxed supernodes, supernodal).
void UseCholmodFactorSettings(cholmod_common& common,
                              SupernodeRelaxation relaxation = SupernodeRelaxation::Cholmod) {
  common.supernodal = CHOLMOD_SUPERNODAL;
  ApplySupernodeRelaxation(common, relaxation);
}

void ExpectSameFactor(const cholmod_factor* mine, const cholmod_factor* theirs) {
  ASSERT_TRUE(mine && theirs && mine->is_super && theirs->is_super);
  const size_t n = theirs->n, nsuper = theirs->nsuper;
  EXPECT_EQ(mine->n, n);
  ASSERT_EQ(mine->nsuper, nsuper);
  EXPECT_EQ(mine->ordering, theirs->ordering);
  EXPECT_EQ(Ints(mine->Perm, n), Ints(theirs->Perm, n));
  EXPECT_EQ(Ints(mine->ColCount, n), Ints(theirs->ColCount, n));
  EXPECT_EQ(Ints(mine->super, nsuper + 1), Ints(theirs->super, nsuper + 1));
  EXPECT_EQ(Ints(mine->pi, nsuper + 1), Ints(theirs->pi, nsuper + 1));
  EXPECT_EQ(Ints(mine->px, nsuper + 1), Ints(theirs->px, nsuper + 1));
  ASSERT_EQ(mine->ssize, theirs->ssize);
  EXPECT_EQ(Ints(mine->s, theirs->ssize), Ints(theirs->s, theirs->ssize));
  EXPECT_EQ(mine->xsize, theirs->xsize);
  EXPECT_EQ(mine->maxcsize, theirs->maxcsize);
  EXPECT_EQ(mine->maxesize, theirs->maxesize);
  EXPECT_EQ(mine->is_ll, theirs->is_ll);
  EXPECT_EQ(mine->xtype, theirs->xtype);
}

// AnalyzeInGivenOrder against cholmod_analyze_p for one matrix and order.
void ExpectAnalysisAsCholmodGives(const SparseMatrix& upper, const std::vector<int>& perm,
                                  bool expectNodeBlocked,
                                  SupernodeRelaxation relaxation = SupernodeRelaxation::Cholmod) {
  QuietCholmodCommon mineQuiet, theirsQuiet;
  UseCholmodFactorSettings(mineQuiet.common, relaxation);
  UseCholmodFactorSettings(theirsQuiet.common, relaxation);
  cholmod_common& theirsCommon = theirsQuiet.common;
  theirsCommon.nmethods = 1;
  theirsCommon.method[0].ordering = CHOLMOD_GIVEN;
  theirsCommon.postorder = 1;
  bool nodeBlocked = !expectNodeBlocked;
  cholmod_factor* mine = AnalyzeInGivenOrder(upper, perm, mineQuiet.common, &nodeBlocked);
  cholmod_sparse view = ViewUpper(upper);
  cholmod_factor* theirs =
      cholmod_analyze_p(&view, const_cast<int*>(perm.data()), nullptr, 0, &theirsCommon);
  EXPECT_EQ(nodeBlocked, expectNodeBlocked);
  ExpectSameFactor(mine, theirs);
  EXPECT_EQ(mineQuiet.common.lnz, theirsCommon.lnz);
  EXPECT_EQ(mineQuiet.common.fl, theirsCommon.fl);
  cholmod_free_factor(&mine, &mineQuiet.common);
  cholmod_free_factor(&theirs, &theirsCommon);
}

std::shared_ptr<const CondensedSystem> ShellSystem() {
  std::shared_ptr<const CondensedSystem> system;
  const Status precomputed = Precompute(ShellRequest(10, 4), system);
  EXPECT_TRUE(precomputed.ok && system) << precomputed.message;
  return system;
}

TEST(CholmodAnalysis, NodeBlockedStiffnessInANodeOrder) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  const int freeNodes = system->layout.freeNodes();
  for (const std::vector<char>& marks :
       {NodesCoupledTo(system->kfr, freeNodes, 3), std::vector<char>{}}) {
    FillReducingOrdering ordering;
    ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, marks, ordering).ok);
    for (SupernodeRelaxation relaxation :
         {SupernodeRelaxation::Cholmod, SupernodeRelaxation::Coarse})
      ExpectAnalysisAsCholmodGives(system->kff, ordering.permutation, true, relaxation);
  }
}

// An order that splits a node's DOFs, and a matrix with one block entry missing, take the general
// path and give CHOLMOD's factor too.
TEST(CholmodAnalysis, OrdersAndMatricesThatAreNotNodeBlocked) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  FillReducingOrdering ordering;
  ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, {}, ordering).ok);
  std::vector<int> swapped = ordering.permutation;
  std::swap(swapped[3], swapped[4]); // a node's DOFs out of order
  ExpectAnalysisAsCholmodGives(system->kff, swapped, false);

  SparseMatrix missing = system->kff; // drop the first off-diagonal entry of a late column
  const int column = static_cast<int>(missing.cols()) - 1;
  for (SparseMatrix::InnerIterator it(missing, column); it; ++it)
    if (it.row() != column) {
      missing.coeffRef(it.row(), column) = 0.0;
      break;
    }
  missing.prune([](Eigen::Index, Eigen::Index, double value) { return value != 0.0; });
  missing.makeCompressed();
  ASSERT_LT(missing.nonZeros(), system->kff.nonZeros());
  ExpectAnalysisAsCholmodGives(missing, ordering.permutation, false);
}

TEST(CholmodAnalysis, CholmodFactorUsesIt) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  FillReducingOrdering ordering;
  ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, {}, ordering).ok);
  size_t supernodes[2] = {0, 0};
  int k = 0;
  for (SupernodeRelaxation relaxation :
       {SupernodeRelaxation::Cholmod, SupernodeRelaxation::Coarse}) {
    CholmodFactor factor;
    if (relaxation != SupernodeRelaxation::Cholmod) // CHOLMOD's settings are the default
      factor.setSupernodeRelaxation(relaxation);
    ASSERT_TRUE(factor.analyze(system->kff, &ordering).ok);
    QuietCholmodCommon quiet;
    UseCholmodFactorSettings(quiet.common, relaxation);
    cholmod_factor* direct = AnalyzeInGivenOrder(system->kff, ordering.permutation, quiet.common);
    ExpectSameFactor(factor.cholmodFactor(), direct);
    EXPECT_EQ(factor.factorNonzeros(), quiet.common.lnz);
    supernodes[k++] = direct->nsuper;
    cholmod_free_factor(&direct, &quiet.common);
  }
  EXPECT_LT(supernodes[1], supernodes[0]); // coarse: fewer, larger supernodes
}

// A factor that copies another's analysis (analyzeLike) has the same symbolic factor, factors
// the matrix to the same values bit for bit and solves it alike; the analysis it copied stays
// as it was, and copying nothing, or itself, is refused.
TEST(CholmodAnalysis, AnalyzeLikeCopiesTheAnalysis) {
  const auto system = ShellSystem();
  ASSERT_TRUE(system);
  FillReducingOrdering ordering;
  ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, {}, ordering).ok);
  CholmodFactor analysed, own, copy;
  ASSERT_TRUE(analysed.analyze(system->kff, &ordering).ok);
  ASSERT_TRUE(own.analyze(system->kff, &ordering).ok);
  ASSERT_TRUE(copy.analyzeLike(analysed).ok);
  ExpectSameFactor(copy.cholmodFactor(), own.cholmodFactor());
  EXPECT_EQ(copy.eliminationPosition(), own.eliminationPosition());
  ASSERT_TRUE(own.factorize(system->kff).ok);
  ASSERT_TRUE(copy.factorize(system->kff).ok);
  const cholmod_factor* a = own.cholmodFactor();
  const cholmod_factor* b = copy.cholmodFactor();
  ASSERT_EQ(a->xsize, b->xsize);
  const double* ax = static_cast<const double*>(a->x);
  const double* bx = static_cast<const double*>(b->x);
  EXPECT_TRUE(std::equal(ax, ax + a->xsize, bx)) << "the same factor values";
  EXPECT_FALSE(analysed.isFactorized()) << "the copied analysis is left as it was";
  const Eigen::VectorXd rhs = Eigen::VectorXd::Random(system->kff.rows());
  Eigen::MatrixXd x1, x2;
  ASSERT_TRUE(own.solve(rhs, x1).ok);
  ASSERT_TRUE(copy.solve(rhs, x2).ok);
  EXPECT_EQ(x1, x2);

  CholmodFactor unanalysed, another;
  EXPECT_FALSE(another.analyzeLike(unanalysed).ok);
  EXPECT_FALSE(copy.analyzeLike(copy).ok);
}

} // namespace
