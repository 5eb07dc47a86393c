// SPDX-License-Identifier: BSD-3-Clause
// The memory budget: sizes known after the symbolic analysis are checked before the factor or the
// dense response is allocated.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/MemoryBudget.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

SystemInfo Unlimited(PrecomputeRequest request) {
  request.options.memoryBudgetBytes = 1e15;
  std::shared_ptr<const CondensedSystem> system;
  const Status s = Precompute(request, system);
  EXPECT_TRUE(s.ok) << s.message;
  return system ? Describe(*system) : SystemInfo();
}

} // namespace

TEST(MemoryBudget, AvailableMemoryIsReadFromTheSystem) {
  EXPECT_GT(AvailableMemoryBytes(), 0.0);
  EXPECT_EQ(MemoryBudgetBytes(1234.0), 1234.0);
  EXPECT_GT(MemoryBudgetBytes(0.0), 0.0);
}

TEST(MemoryBudget, AFactorOverTheBudgetIsAClearErrorBeforeFactorization) {
  PrecomputeRequest request = ShellRequest(4, 2);
  const SystemInfo full = Unlimited(request);
  ASSERT_GT(full.factorBytes, 0.0);
  request.options.memoryBudgetBytes = 0.5 * full.factorBytes;
  std::shared_ptr<const CondensedSystem> system;
  const Status s = Precompute(request, system);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(system, nullptr);
  EXPECT_NE(s.message.find("sparse factor would need"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("memory budget"), std::string::npos) << s.message;
}

TEST(MemoryBudget, AutoKeepsTheFactorWhenTheDenseResponseDoesNotFit) {
  PrecomputeRequest request = ShellRequest(4, 2);
  request.options.method = SolveMethod::DenseResponse;
  const SystemInfo dense = Unlimited(request);
  ASSERT_EQ(dense.method, SolveMethod::DenseResponse);
  ASSERT_GT(dense.responseBytes, 0.0);
  // Room for the factor, not for the response beside it.
  const double budget = dense.factorBytes + 0.5 * dense.responseBytes;

  request.options.method = SolveMethod::Auto;
  request.options.memoryBudgetBytes = budget;
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  const SystemInfo info = Describe(*system);
  EXPECT_EQ(info.method, SolveMethod::CachedFactor) << info.choiceReason;
  EXPECT_EQ(info.responseBytes, 0.0);
  EXPECT_NE(info.choiceReason.find("budget"), std::string::npos) << info.choiceReason;

  // Still exact: the cheaper path gives the reference answer.
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  SolveResult cached, reference;
  ASSERT_TRUE(Solve(*system, input, cached).ok);
  ASSERT_TRUE(SolveFullReference(request, input, reference).ok);
  EXPECT_LT(RelativeMaxDifference(cached.keptDisplacement, reference.keptDisplacement), 1e-10);

  request.options.method = SolveMethod::DenseResponse;
  s = Precompute(request, system);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(system, nullptr);
  EXPECT_NE(s.message.find("DenseResponse response would need"), std::string::npos) << s.message;
}

TEST(MemoryBudget, TheFactorEstimateCoversTheFactorsNonzeros) {
  const SystemInfo info = Unlimited(ShellRequest(4, 2));
  EXPECT_GE(info.factorBytes, 8.0 * info.factorNonzeros);
  EXPECT_LT(info.factorBytes, 64.0 * info.factorNonzeros + 1e6);
}
