// SPDX-License-Identifier: BSD-3-Clause
// The rigid-segment path (SolveMethod::RigidSegments) against the general dense response and the
// reference full solve, for rigid-only and mixed plans.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/DeformationCheck.h"
#include "Support/FEMTestScenes.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

// A rotation of a few degrees about an oblique axis through `pivot`, then a translation.
SegmentTransform RigidMove(const Eigen::Vector3d& axis, double degrees,
                           const Eigen::Vector3d& pivot, const Eigen::Vector3d& translation) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  SegmentTransform t;
  t.leftCols<3>() = r;
  t.col(3) = pivot - r * pivot + translation;
  return t;
}

// The ROI of the shell scene cut into segments by height: z above `z1` segment 1, between `z2`
// and `z1` segment 2 (when `two`), the rest general (segment 0) when `mixed`, else segment 1.
struct Plan {
  PrecomputeRequest request;
  SolveInput input;
};

Plan MakePlan(bool two, bool mixed) {
  Plan plan;
  plan.request = ShellRequest(5, 3);
  PrecomputeRequest& r = plan.request;
  const RowVectors3d general = SmoothRoiField(r, 0.5);
  double zMin = 1e300, zMax = -1e300;
  for (int node : r.sets.movable) {
    zMin = std::min(zMin, r.mesh.points(node, 2));
    zMax = std::max(zMax, r.mesh.points(node, 2));
  }
  const double z1 = zMin + 0.6 * (zMax - zMin), z2 = zMin + 0.3 * (zMax - zMin);
  plan.input.segmentTransforms = {RigidMove({0.3, 1.0, 0.2}, 4.0, {0, 0, 90}, {1.5, -0.5, 2.0})};
  if (two)
    plan.input.segmentTransforms.push_back(
        RigidMove({1.0, 0.0, 0.4}, -3.0, {10, 0, 80}, {-1.0, 0.7, 0.3}));
  plan.input.movableDisplacement.resize(static_cast<Eigen::Index>(r.sets.movable.size()), 3);
  for (size_t k = 0; k < r.sets.movable.size(); ++k) {
    const double z = r.mesh.points(r.sets.movable[k], 2);
    int segment = z >= z1 ? 1 : (two && z >= z2 ? 2 : (mixed ? 0 : 1));
    r.sets.movableSegment.push_back(segment);
    const Eigen::Vector3d x = r.mesh.points.row(r.sets.movable[k]).transpose();
    if (segment == 0) {
      plan.input.movableDisplacement.row(k) = general.row(k);
    } else {
      const SegmentTransform& t = plan.input.segmentTransforms[segment - 1];
      plan.input.movableDisplacement.row(k) = (t.leftCols<3>() * x + t.col(3) - x).transpose();
    }
  }
  return plan;
}

// Solves the plan with the rigid path (Auto), the general dense response and the reference.
void ExpectRigidEqualsGeneral(Plan plan, int segments, long long generalNodes, bool loads) {
  if (loads)
    plan.input.gravity = Eigen::Vector3d(0.0, -9810.0, 0.0);
  std::shared_ptr<const CondensedSystem> rigid, dense;
  Status s = Precompute(plan.request, rigid);
  ASSERT_TRUE(s.ok) << s.message;
  const SystemInfo info = Describe(*rigid);
  EXPECT_EQ(info.method, SolveMethod::RigidSegments) << info.choiceReason;
  // 12 columns per segment plus 3 per general movable node, not one per ROI DOF.
  EXPECT_EQ(info.responseBytes,
            8.0 * double(info.keptDofs) * double(12 * segments + 3 * generalNodes));

  PrecomputeRequest general = plan.request;
  general.options.method = SolveMethod::DenseResponse;
  s = Precompute(general, dense);
  ASSERT_TRUE(s.ok) << s.message;

  SolveResult fast, slow, reference;
  s = Solve(*rigid, plan.input, fast);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(fast.method, SolveMethod::RigidSegments);
  s = Solve(*dense, plan.input, slow);
  ASSERT_TRUE(s.ok) << s.message;
  s = SolveFullReference(plan.request, plan.input, reference);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_LT(RelativeMaxDifference(fast.keptDisplacement, slow.keptDisplacement), 1e-10);
  EXPECT_LT(RelativeMaxDifference(fast.keptDisplacement, reference.keptDisplacement), 1e-10);

  // The interior, recovered by a solve with the cached factor of the same system.
  plan.input.recoverInterior = true;
  SolveResult all;
  s = Solve(*rigid, plan.input, all);
  ASSERT_TRUE(s.ok) << s.message;
  plan.input.recoverInterior = false;
  SolveResult referenceAll;
  PrecomputeRequest request = plan.request;
  SolveInput input = plan.input;
  input.recoverInterior = true;
  ASSERT_TRUE(SolveFullReference(request, input, referenceAll).ok);
  EXPECT_LT(RelativeMaxDifference(all.allDisplacement, referenceAll.allDisplacement), 1e-10);
}

long long GeneralNodes(const NodeSets& sets) {
  return std::count(sets.movableSegment.begin(), sets.movableSegment.end(), 0);
}

} // namespace

TEST(RigidSegments, OneSegmentEqualsGeneralAndReference) {
  Plan plan = MakePlan(false, false);
  ASSERT_EQ(GeneralNodes(plan.request.sets), 0);
  ExpectRigidEqualsGeneral(plan, 1, 0, false);
}

TEST(RigidSegments, TwoSegmentsWithGravityEqualGeneralAndReference) {
  Plan plan = MakePlan(true, false);
  ExpectRigidEqualsGeneral(plan, 2, GeneralNodes(plan.request.sets), true);
}

TEST(RigidSegments, MixedPlanIsExact) {
  Plan plan = MakePlan(true, true);
  const long long general = GeneralNodes(plan.request.sets);
  ASSERT_GT(general, 0);
  ASSERT_LT(general, static_cast<long long>(plan.request.sets.movable.size()));
  ExpectRigidEqualsGeneral(plan, 2, general, false);
}

TEST(RigidSegments, DisplacementsThatMissTheTransformAreRejected) {
  Plan plan = MakePlan(false, true);
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(plan.request, system).ok);
  size_t k = 0;
  while (plan.request.sets.movableSegment[k] != 1)
    ++k;
  plan.input.movableDisplacement(static_cast<Eigen::Index>(k), 1) += 1e-3;
  SolveResult result;
  Status s = Solve(*system, plan.input, result);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("differs"), std::string::npos) << s.message;
  // Without transforms the rigid path cannot run.
  plan = MakePlan(false, true);
  plan.input.segmentTransforms.clear();
  s = Solve(*system, plan.input, result);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("transform"), std::string::npos) << s.message;
}

TEST(RigidSegments, RequestedWithoutSegmentsIsAnError) {
  PrecomputeRequest request = ShellRequest(3, 2);
  request.options.method = SolveMethod::RigidSegments;
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("segment"), std::string::npos) << s.message;
  request.sets.movableSegment.assign(request.sets.movable.size() - 1, 1);
  s = Precompute(request, system);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("movableSegment"), std::string::npos) << s.message;
}

// The per-edit strain check of the rigid path stops early on bounds (DeformationCheck.h): every
// bound must hold on the recovered field, and the result must equal checking every cell, for a
// small move and for one so large that cells invert.
TEST(RigidSegments, BoundedStrainCheckEqualsCheckingEveryCell) {
  for (double stretch : {1.0, 40.0}) {
    for (bool mixed : {false, true}) {
      Plan plan = MakePlan(true, mixed);
      for (SegmentTransform& t : plan.input.segmentTransforms) {
        t.col(3) *= stretch;
        t.leftCols<3>() =
            Eigen::Matrix3d::Identity() + stretch * (t.leftCols<3>() - Eigen::Matrix3d::Identity());
      }
      const RowVectors3d& points = plan.request.mesh.points;
      for (size_t k = 0; k < plan.request.sets.movable.size(); ++k) {
        const int s = plan.request.sets.movableSegment[k];
        const Eigen::Vector3d x = points.row(plan.request.sets.movable[k]).transpose();
        if (s > 0) {
          const SegmentTransform& t = plan.input.segmentTransforms[s - 1];
          plan.input.movableDisplacement.row(k) = (t.leftCols<3>() * x + t.col(3) - x).transpose();
        } else {
          plan.input.movableDisplacement.row(k) *= stretch;
        }
      }
      // Every unconstrained node kept, so that every cell is checkable on a kept-only solve.
      std::vector<char> constrained(points.rows(), 0);
      for (int node : plan.request.sets.constrained)
        constrained[node] = 1;
      plan.request.sets.kept.clear();
      for (int node = 0; node < points.rows(); ++node)
        if (!constrained[node])
          plan.request.sets.kept.push_back(node);
      std::shared_ptr<const CondensedSystem> rigid, dense;
      ASSERT_TRUE(Precompute(plan.request, rigid).ok);
      ASSERT_EQ(rigid->method, SolveMethod::RigidSegments);
      ASSERT_FALSE(rigid->boundedCells.empty())
          << "no ordered check: parameters " << rigid->response.cols() << ", checkable cells "
          << rigid->checkableCells.size();
      PrecomputeRequest general = plan.request;
      general.options.method = SolveMethod::DenseResponse;
      ASSERT_TRUE(Precompute(general, dense).ok);

      SolveResult fast, slow, all;
      ASSERT_TRUE(Solve(*rigid, plan.input, fast).ok);
      ASSERT_TRUE(Solve(*dense, plan.input, slow).ok);
      EXPECT_NEAR(fast.largestStrain, slow.largestStrain, 1e-12 * slow.largestStrain);
      EXPECT_EQ(fast.invertedCells, slow.invertedCells);
      EXPECT_EQ(fast.warnings.size(), slow.warnings.size());
      if (stretch > 1.0)
        EXPECT_GT(slow.invertedCells, 0) << "the large move should invert cells";

      // Each bound holds on the field the solve represents.
      SolveInput input = plan.input;
      input.recoverInterior = true;
      ASSERT_TRUE(Solve(*rigid, input, all).ok);
      const Eigen::VectorXd p = SegmentParameters(plan.request.sets, plan.input.segmentTransforms,
                                                  plan.input.movableDisplacement);
      const double scale = ScaledParameterNorm(*rigid, p);
      double previous = std::numeric_limits<double>::infinity();
      for (const CondensedSystem::BoundedCell& cell : rigid->boundedCells) {
        EXPECT_LE(cell.gain, previous);
        previous = cell.gain;
        Eigen::Matrix3d du;
        for (int j = 0; j < 3; ++j)
          du.col(j) = (all.allDisplacement.row(plan.request.mesh.tets(cell.cell, j + 1)) -
                       all.allDisplacement.row(plan.request.mesh.tets(cell.cell, 0)))
                          .transpose();
        EXPECT_LE((du * cell.inverseEdges).norm(), cell.gain * scale * (1.0 + 1e-9) + 1e-12)
            << "cell " << cell.cell;
      }
    }
  }
}
