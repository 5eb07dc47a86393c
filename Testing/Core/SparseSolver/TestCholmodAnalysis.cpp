// CholmodFactor::analyze with a given ordering analyses a copy of the pattern permuted by that
// ordering (so that CHOLMOD transposes a matrix already in elimination order): its symbolic factor
// must be the one CHOLMOD makes from the original matrix with the same ordering (CHOLMOD_GIVEN,
// postordered), array for array.
#include "CondensedFEM/CondensedSystem.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "Support/FEMTestScenes.h"

#include <cholmod.h>
#include <gtest/gtest.h>

#include <vector>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

std::vector<int> Ints(const void* data, size_t count) {
  const int* begin = static_cast<const int*>(data);
  return std::vector<int>(begin, begin + count);
}

TEST(CholmodAnalysis, InGivenOrderEqualsCholmodsOwnAnalysisOfThatOrdering) {
  std::shared_ptr<const CondensedSystem> system;
  const Status precomputed = Precompute(ShellRequest(10, 4), system);
  ASSERT_TRUE(precomputed.ok && system) << precomputed.message;
  const int freeNodes = system->layout.freeNodes();
  for (const std::vector<char>& marks : {NodesCoupledTo(system->kfr, freeNodes, 3), std::vector<char>{}}) {
    FillReducingOrdering ordering;
    ASSERT_TRUE(OrderNodesWithTrailing(system->kff, 3, marks, ordering).ok);
    CholmodFactor factor;
    ASSERT_TRUE(factor.analyze(system->kff, &ordering).ok);
    const cholmod_factor* mine = factor.cholmodFactor();
    ASSERT_TRUE(mine && mine->is_super);

    // CHOLMOD's own analysis with the same settings as CholmodFactor's.
    QuietCholmodCommon quiet;
    cholmod_common& common = quiet.common;
    common.supernodal = CHOLMOD_SUPERNODAL;
    const int nrelax[3] = {16, 64, 128};
    const double zrelax[3] = {0.9, 0.3, 0.1};
    for (int k = 0; k < 3; ++k) {
      common.nrelax[k] = nrelax[k];
      common.zrelax[k] = zrelax[k];
    }
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_GIVEN;
    common.postorder = 1;
    cholmod_sparse view = ViewUpper(system->kff);
    cholmod_factor* theirs =
        cholmod_analyze_p(&view, const_cast<int*>(ordering.permutation.data()), nullptr, 0, &common);
    ASSERT_TRUE(theirs && theirs->is_super);
    const size_t n = theirs->n;
    EXPECT_EQ(mine->n, n);
    EXPECT_EQ(mine->nsuper, theirs->nsuper);
    EXPECT_EQ(mine->ordering, theirs->ordering);
    EXPECT_EQ(Ints(mine->Perm, n), Ints(theirs->Perm, n));
    EXPECT_EQ(Ints(mine->ColCount, n), Ints(theirs->ColCount, n));
    if (mine->nsuper == theirs->nsuper) {
      EXPECT_EQ(Ints(mine->super, n == 0 ? 0 : theirs->nsuper + 1), Ints(theirs->super, theirs->nsuper + 1));
      EXPECT_EQ(Ints(mine->pi, theirs->nsuper + 1), Ints(theirs->pi, theirs->nsuper + 1));
      EXPECT_EQ(Ints(mine->px, theirs->nsuper + 1), Ints(theirs->px, theirs->nsuper + 1));
      EXPECT_EQ(Ints(mine->s, theirs->ssize), Ints(theirs->s, theirs->ssize));
    }
    EXPECT_EQ(mine->xsize, theirs->xsize);
    EXPECT_EQ(mine->maxcsize, theirs->maxcsize);
    EXPECT_EQ(mine->maxesize, theirs->maxesize);
    cholmod_free_factor(&theirs, &common);
  }
}

} // namespace
