// SPDX-License-Identifier: BSD-3-Clause
// Sliding contact (NodeSets::sliding): only the normal displacement is prescribed. Checked against
// the analytic uniaxial solution of a block between frictionless walls, and against CalculiX on a
// curved surface (*TRANSFORM + *BOUNDARY on the local normal DOF).
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Support/BoxMeshGenerator.h"
#include "Support/CalculixRunner.h"
#include "Support/FEMTestScenes.h"

#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

constexpr double kLx = 20.0, kLy = 16.0, kLz = 12.0, kPress = 0.6, kNu = 0.3;

PrecomputeRequest PressedBlock() {
  return PressedBlockRequest(kLx, kLy, kLz, kNu);
}

// u = (nu e x, nu e y, -e z) with e = kPress / kLz: uniaxial compression, lateral expansion free.
RowVectors3d Uniaxial(const RowVectors3d& points) {
  const double strain = kPress / kLz;
  RowVectors3d u(points.rows(), 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    u.row(i) << kNu * strain * points(i, 0), kNu * strain * points(i, 1), -strain * points(i, 2);
  return u;
}

void ExpectUniaxial(SolveMethod method, bool recoverInterior) {
  PrecomputeRequest request = PressedBlock();
  request.options.method = method;
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  SolveInput input;
  // The plate's full motion may carry a tangential part: sliding nodes take only the normal one.
  input.movableDisplacement =
      RowVectors3d::Zero(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  input.movableDisplacement.col(0).setConstant(0.25);
  input.movableDisplacement.col(2).setConstant(-kPress);
  input.recoverInterior = recoverInterior;
  SolveResult result;
  s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok) << s.message;
  const RowVectors3d exact = Uniaxial(request.mesh.points);
  EXPECT_LT(RelativeMaxDifference(result.keptDisplacement, exact), 1e-10);
  if (recoverInterior)
    EXPECT_LT(RelativeMaxDifference(result.allDisplacement, exact), 1e-10);
}

} // namespace

TEST(SlidingContact, BlockBetweenFrictionlessWallsIsUniaxialDenseResponse) {
  ExpectUniaxial(SolveMethod::DenseResponse, false);
}

TEST(SlidingContact, BlockBetweenFrictionlessWallsIsUniaxialCachedFactor) {
  ExpectUniaxial(SolveMethod::CachedFactor, true);
}

TEST(SlidingContact, SlidingNodesKeepTheirNormalValueAndMoveTangentially) {
  RowVectors3d push;
  PrecomputeRequest request = SlidingShellRequest(1.5, push);
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  // Turned and pinned DOFs change K_FF after the assembly: ordered from the separated blocks.
  EXPECT_FALSE(system->info.orderedBesideAssembly);
  SolveInput input;
  input.movableDisplacement = push;
  SolveResult result;
  s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok) << s.message;
  std::vector<int> keptRow(request.mesh.numPoints(), -1);
  for (size_t k = 0; k < request.sets.kept.size(); ++k)
    keptRow[request.sets.kept[k]] = static_cast<int>(k);
  std::vector<int> movableRow(request.mesh.numPoints(), -1);
  for (size_t k = 0; k < request.sets.movable.size(); ++k)
    movableRow[request.sets.movable[k]] = static_cast<int>(k);
  double largestTangential = 0.0;
  for (size_t k = 0; k < request.sets.sliding.size(); ++k) {
    const int node = request.sets.sliding[k];
    const Eigen::Vector3d n = request.sets.slidingNormal[k];
    const Eigen::Vector3d u = result.keptDisplacement.row(keptRow[node]).transpose();
    const double expected =
        movableRow[node] >= 0 ? push.row(movableRow[node]).dot(n.transpose()) : 0.0;
    EXPECT_NEAR(u.dot(n), expected, 1e-12);
    largestTangential = std::max(largestTangential, (u - u.dot(n) * n).norm());
  }
  EXPECT_GT(largestTangential, 0.05); // the tissue slides, it is not tied
}

TEST(SlidingContact, CurvedSurfaceAgreesWithCalculix) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "ccx (CalculiX) is not installed";
  RowVectors3d push;
  PrecomputeRequest request = SlidingShellRequest(1.5, push);
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  SolveInput input;
  input.movableDisplacement = push;
  SolveResult result;
  s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok) << s.message;
  const std::string dir =
      (std::filesystem::temp_directory_path() / "faceplan_sliding_ccx").string();
  std::filesystem::create_directories(dir);
  const bench::CalculixResult ccx = bench::RunCalculix(request, push, dir, 1);
  ASSERT_TRUE(ccx.ok) << ccx.error;
  EXPECT_LT(RelativeMaxDifference(result.keptDisplacement, ccx.keptDisplacement), 1e-6);
}

TEST(SlidingContact, InvalidSlidingSetsAreErrors) {
  PrecomputeRequest request = PressedBlock();
  std::shared_ptr<const CondensedSystem> system;
  PrecomputeRequest bad = request;
  bad.sets.slidingNormal.pop_back();
  EXPECT_FALSE(Precompute(bad, system).ok);
  bad = request;
  bad.sets.slidingNormal[0] = Eigen::Vector3d(0.0, 0.0, 2.0);
  Status s = Precompute(bad, system);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("unit"), std::string::npos) << s.message;
  bad = request;
  bad.options.elementOrder = ElementOrder::Quadratic;
  EXPECT_FALSE(Precompute(bad, system).ok);
  SolveResult result;
  SolveInput input;
  input.movableDisplacement =
      RowVectors3d::Zero(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  s = SolveFullReference(request, input, result);
  EXPECT_FALSE(s.ok);
}
