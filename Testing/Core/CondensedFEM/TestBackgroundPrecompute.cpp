// SPDX-License-Identifier: BSD-3-Clause
#include "Common/RelativeDifference.h"
#include "CondensedFEM/BackgroundPrecompute.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

TEST(BackgroundPrecompute, WaitGivesTheSameSystemAsADirectPrecompute) {
  PrecomputeRequest request = ShellRequest(4, 2);
  BackgroundPrecompute background;
  background.start(request);
  std::shared_ptr<const CondensedSystem> fromThread, direct;
  ASSERT_TRUE(background.wait(fromThread).ok);
  ASSERT_TRUE(background.ready());
  ASSERT_TRUE(Precompute(request, direct).ok);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  SolveResult a, b;
  ASSERT_TRUE(Solve(*fromThread, input, a).ok);
  ASSERT_TRUE(Solve(*direct, input, b).ok);
  EXPECT_EQ((a.keptDisplacement - b.keptDisplacement).cwiseAbs().maxCoeff(), 0.0);
}

TEST(BackgroundPrecompute, RestartPublishesOnlyTheLatestRequest) {
  PrecomputeRequest first = ShellRequest(8, 3);
  PrecomputeRequest second = ShellRequest(3, 2, 5000.0, 0.3);
  BackgroundPrecompute background;
  background.start(first);
  background.start(second); // supersedes the first at once
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(background.wait(system).ok);
  EXPECT_EQ(Describe(*system).keptDofs, 3LL * static_cast<long long>(second.sets.kept.size()));
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(second);
  SolveResult fromCache, reference;
  ASSERT_TRUE(Solve(*system, input, fromCache).ok);
  ASSERT_TRUE(SolveFullReference(second, input, reference).ok);
  EXPECT_LT(RelativeMaxDifference(fromCache.keptDisplacement, reference.keptDisplacement), 1e-10);
}

TEST(BackgroundPrecompute, CancelReportsCancelled) {
  BackgroundPrecompute background;
  background.start(ShellRequest(10, 4));
  background.cancel();
  std::shared_ptr<const CondensedSystem> system;
  const Status s = background.wait(system);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "cancelled");
  EXPECT_EQ(system, nullptr);
}

TEST(BackgroundPrecompute, ErrorsArriveThroughWait) {
  PrecomputeRequest bad = ShellRequest(2, 1);
  bad.materials.poissonRatio[0] = 0.5;
  BackgroundPrecompute background;
  background.start(bad);
  std::shared_ptr<const CondensedSystem> system;
  const Status s = background.wait(system);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("Poisson"), std::string::npos);
}
