// SPDX-License-Identifier: BSD-3-Clause
// The policies the filters take from Core: which requests may share a precompute, unit scaling and
// verification against an independent solve.
#include "CondensedFEM/PhysicalUnits.h"
#include "CondensedFEM/RequestIdentity.h"
#include "CondensedFEM/Verify.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

#include <functional>
#include <vector>

namespace faceplan {
namespace {

TEST(RequestIdentity, EveryOptionChangeGivesANewRequest) {
  const PrecomputeRequest base = testing::ShellRequest(2, 2);
  EXPECT_TRUE(SameRequest(base, base));
  const std::vector<std::function<void(PrecomputeRequest&)>> changes = {
      [](PrecomputeRequest& r) { r.options.method = SolveMethod::CachedFactor; },
      [](PrecomputeRequest& r) { r.options.denseResponseBudgetBytes *= 0.5; },
      [](PrecomputeRequest& r) { r.options.backend = MakeCpuBackend(); },
      [](PrecomputeRequest& r) { r.options.responseBlockColumns = 7; },
      [](PrecomputeRequest& r) { r.options.elementOrder = ElementOrder::Quadratic; },
      [](PrecomputeRequest& r) {
        r.options.midEdgeProjection = [](const Eigen::Vector3d& m, int, int) { return m; };
      },
      [](PrecomputeRequest& r) { r.options.quadraticMeanDilatation = false; },
      [](PrecomputeRequest& r) { r.options.sliverQualityThreshold = 0.5; },
      [](PrecomputeRequest& r) { r.options.residualTolerance = 1e-6; },
      [](PrecomputeRequest& r) { r.options.maxRefinementSteps = 0; },
      [](PrecomputeRequest& r) { r.options.responseTolerance = 1e-3; },
      [](PrecomputeRequest& r) { r.options.strainWarningLimit = 0.0; },
      [](PrecomputeRequest& r) { r.mesh.points(0, 0) += 1e-9; },
      [](PrecomputeRequest& r) { std::swap(r.mesh.tets(0, 0), r.mesh.tets(0, 1)); },
      [](PrecomputeRequest& r) { r.materials.youngsModulus[0] *= 2.0; },
      [](PrecomputeRequest& r) { r.materials.poissonRatio[0] = 0.3; },
      [](PrecomputeRequest& r) { r.materials.density[0] = 1.0; },
      [](PrecomputeRequest& r) { r.sets.kept.pop_back(); },
      [](PrecomputeRequest& r) { r.sets.movable.pop_back(); },
      [](PrecomputeRequest& r) { r.sets.constrained.push_back(r.sets.kept.front()); },
      [](PrecomputeRequest& r) { r.sets.movableSegment.assign(r.sets.movable.size(), 1); },
      [](PrecomputeRequest& r) { r.sets.sliding.push_back(r.sets.constrained.front()); },
      [](PrecomputeRequest& r) {
        r.sets.sliding.push_back(r.sets.constrained.front());
        r.sets.slidingNormal.push_back(Eigen::Vector3d::UnitZ());
      },
  };
  for (size_t k = 0; k < changes.size(); ++k) {
    PrecomputeRequest changed = base;
    changes[k](changed);
    EXPECT_FALSE(SameRequest(base, changed)) << "change " << k << " was not noticed";
  }
}

TEST(PhysicalUnits, MillimetresScaleModulusAndDensity) {
  Materials si = Materials::Uniform(15000.0, 0.45, 1100.0);
  Materials mm;
  ASSERT_TRUE(MaterialsInMeshUnits(si, 0.001, mm).ok);
  EXPECT_DOUBLE_EQ(mm.youngsModulus[0], 15000.0 * 1e-6); // N/mm^2
  EXPECT_DOUBLE_EQ(mm.density[0], 1100.0 * 1e-9);        // kg/mm^3
  EXPECT_DOUBLE_EQ(mm.poissonRatio[0], 0.45);
  for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    const Status s = MaterialsInMeshUnits(si, bad, mm);
    EXPECT_FALSE(s.ok);
    EXPECT_NE(s.message.find("length unit"), std::string::npos) << s.message;
  }
}

TEST(Verify, CondensedSolveAgreesWithReferenceAndAPerturbedOneDoesNot) {
  PrecomputeRequest request = testing::ShellRequest(2, 2);
  SolveInput input;
  input.movableDisplacement = testing::SmoothRoiField(request);
  input.recoverInterior = true;
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  SolveResult result;
  ASSERT_TRUE(Solve(*system, input, result).ok);
  double error = -1.0;
  ASSERT_TRUE(VerifyAgainstReference(request, input, result, error).ok);
  EXPECT_LT(error, 1e-10);
  result.allDisplacement(0, 0) += 1e-3 * result.keptDisplacement.cwiseAbs().maxCoeff();
  ASSERT_TRUE(VerifyAgainstReference(request, input, result, error).ok);
  EXPECT_GT(error, 1e-4);
  result.keptDisplacement(0, 1) = std::nan("");
  ASSERT_TRUE(VerifyAgainstReference(request, input, result, error).ok);
  EXPECT_TRUE(std::isinf(error));
}

} // namespace
} // namespace faceplan
