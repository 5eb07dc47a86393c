// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The precomputed large-deformation system of a request, as the tests make it. Uses GoogleTest
// (EXPECT_TRUE), so it is a header for test executables only: FacePlanTestSupport does not link
// GoogleTest.
#include "CondensedFEM/PrecomputedLargeDeformation.h"

#include <gtest/gtest.h>

#include <memory>

namespace faceplan::testing {

// Null (with a failed expectation naming why) when the precompute fails.
inline std::shared_ptr<LargeDeformationSystem>
Precomputed(const PrecomputeRequest& request, PrecomputedLargeDeformationOptions options = {}) {
  std::shared_ptr<LargeDeformationSystem> system;
  const Status s = PrecomputeLargeDeformation(request, options, system);
  EXPECT_TRUE(s.ok) << s.message;
  return system;
}

} // namespace faceplan::testing
