// SPDX-License-Identifier: BSD-3-Clause
// The condensed paths must equal the reference full solve (no condensation) on several meshes.
#include "Common/RelativeDifference.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

struct Case {
  int subdivisions, layers;
  bool loads;
  SolveMethod method;
  bool interior;
};

class CondensedVsReference : public ::testing::TestWithParam<Case> {};

} // namespace

TEST_P(CondensedVsReference, AgreesTo1e10) {
  const Case c = GetParam();
  PrecomputeRequest request = ShellRequest(c.subdivisions, c.layers);
  // Two tissues: every third cell ten times stiffer.
  request.materials.youngsModulus = Eigen::VectorXd::Constant(request.mesh.numTets(), 3000.0);
  for (Eigen::Index e = 0; e < request.mesh.numTets(); e += 3)
    request.materials.youngsModulus[e] = 30000.0;
  request.options.method = c.method;
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  input.recoverInterior = c.interior;
  if (c.loads) {
    input.gravity = Eigen::Vector3d(0.0, -9810.0, 0.0); // mm/s^2 with density in kg/mm^3
    input.nodalLoads = RowVectors3d::Zero(request.mesh.numPoints(), 3);
    for (int id : request.sets.kept)
      input.nodalLoads.row(id) << 0.01, 0.02, -0.01;
  }
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(Describe(*system).method, c.method);
  SolveResult condensed, reference;
  s = Solve(*system, input, condensed);
  ASSERT_TRUE(s.ok) << s.message;
  input.recoverInterior = true;
  s = SolveFullReference(request, input, reference);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_LT(reference.relativeResidual, 1e-12);
  EXPECT_LT(condensed.relativeResidual, 1e-12);
  EXPECT_LT(RelativeMaxDifference(condensed.keptDisplacement, reference.keptDisplacement), 1e-10);
  if (c.interior)
    EXPECT_LT(RelativeMaxDifference(condensed.allDisplacement, reference.allDisplacement), 1e-10);
  // Solving twice with the cache gives the same answer (the load response is reused).
  SolveResult again;
  input.recoverInterior = c.interior;
  ASSERT_TRUE(Solve(*system, input, again).ok);
  EXPECT_LT(RelativeMaxDifference(again.keptDisplacement, reference.keptDisplacement), 1e-10);
}

INSTANTIATE_TEST_SUITE_P(Meshes, CondensedVsReference,
                         ::testing::Values(Case{3, 2, false, SolveMethod::DenseResponse, false},
                                           Case{3, 2, true, SolveMethod::DenseResponse, false},
                                           Case{4, 3, true, SolveMethod::DenseResponse, true},
                                           Case{4, 3, false, SolveMethod::CachedFactor, false},
                                           Case{6, 2, true, SolveMethod::CachedFactor, true},
                                           Case{6, 2, true, SolveMethod::CachedFactor, false},
                                           Case{5, 4, false, SolveMethod::DenseResponse, true}));

TEST(CondensedVsReference, AutoPicksAndReportsAMethod) {
  PrecomputeRequest request = ShellRequest(4, 2);
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  const SystemInfo info = Describe(*system);
  EXPECT_TRUE(info.method == SolveMethod::DenseResponse ||
              info.method == SolveMethod::CachedFactor);
  EXPECT_FALSE(info.choiceReason.empty());
  EXPECT_EQ(info.keptDofs + info.interiorDofs, info.freeDofs);
}

// An edit that moves only part of the ROI (the dense product then reads only the moved columns)
// equals the reference, and so does the edit after it that moves every ROI node again.
TEST(CondensedVsReference, PartlyMovedRoiEqualsReference) {
  PrecomputeRequest request = ShellRequest(4, 3);
  request.options.method = SolveMethod::DenseResponse;
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  const RowVectors3d smooth = SmoothRoiField(request);
  for (int stride : {5, 1}) {
    SolveInput input;
    input.movableDisplacement = RowVectors3d::Zero(smooth.rows(), 3);
    for (Eigen::Index k = 0; k < smooth.rows(); k += stride)
      input.movableDisplacement.row(k) = smooth.row(k);
    SolveResult condensed, reference;
    ASSERT_TRUE(Solve(*system, input, condensed).ok);
    ASSERT_TRUE(SolveFullReference(request, input, reference).ok);
    EXPECT_LT(RelativeMaxDifference(condensed.keptDisplacement, reference.keptDisplacement), 1e-10)
        << "every " << stride << "th ROI node moved";
  }
}
