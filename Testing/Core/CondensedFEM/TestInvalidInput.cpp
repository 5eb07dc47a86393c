// SPDX-License-Identifier: BSD-3-Clause
// Every invalid input gives a clear error and never a crash, an exception or NaN.
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

std::string PrecomputeError(const PrecomputeRequest& request) {
  std::shared_ptr<const CondensedSystem> system;
  const Status s = Precompute(request, system);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(system, nullptr);
  SolveResult reference;
  SolveInput input;
  input.movableDisplacement =
      RowVectors3d::Zero(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  EXPECT_FALSE(SolveFullReference(request, input, reference).ok);
  return s.message;
}

} // namespace

TEST(InvalidInput, InvertedTetListsItsId) {
  PrecomputeRequest r = ShellRequest(2, 1);
  std::swap(r.mesh.tets(7, 0), r.mesh.tets(7, 1));
  const std::string msg = PrecomputeError(r);
  EXPECT_NE(msg.find("inverted cells 7"), std::string::npos) << msg;
}

TEST(InvalidInput, ZeroVolumeTetListsItsId) {
  PrecomputeRequest r = ShellRequest(2, 1);
  // Duplicate a corner: volume exactly zero.
  r.mesh.tets(11, 3) = r.mesh.tets(11, 0);
  const std::string msg = PrecomputeError(r);
  EXPECT_NE(msg.find("zero-volume cells 11"), std::string::npos) << msg;
}

TEST(InvalidInput, PoissonRatioOutOfRange) {
  for (double nu : {0.5, 0.7, -1.0, std::nan("")}) {
    PrecomputeRequest r = ShellRequest(2, 1);
    r.materials.poissonRatio[0] = nu;
    EXPECT_NE(PrecomputeError(r).find("Poisson ratio"), std::string::npos);
  }
}

TEST(InvalidInput, NonPositiveYoungsModulus) {
  for (double E : {0.0, -5.0, std::nan("")}) {
    PrecomputeRequest r = ShellRequest(2, 1);
    r.materials.youngsModulus[0] = E;
    EXPECT_NE(PrecomputeError(r).find("Young's modulus"), std::string::npos);
  }
}

TEST(InvalidInput, NaNCoordinates) {
  PrecomputeRequest r = ShellRequest(2, 1);
  r.mesh.points(5, 1) = std::nan("");
  const std::string msg = PrecomputeError(r);
  EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
  EXPECT_NE(msg.find("5"), std::string::npos) << msg;
}

TEST(InvalidInput, NoConstrainedNode) {
  PrecomputeRequest r = ShellRequest(2, 1);
  r.sets.constrained.clear();
  r.sets.movable.clear();
  EXPECT_NE(PrecomputeError(r).find("no constrained node"), std::string::npos);
}

TEST(InvalidInput, FreeComponentNamedWithCellsAndBounds) {
  PrecomputeRequest r = ShellRequest(2, 1);
  // A detached tetrahedron far away, tied to nothing.
  const Eigen::Index n = r.mesh.numPoints(), m = r.mesh.numTets();
  r.mesh.points.conservativeResize(n + 4, 3);
  r.mesh.points.bottomRows(4) << 500, 0, 0, 501, 0, 0, 500, 1, 0, 500, 0, 1;
  r.mesh.tets.conservativeResize(m + 1, 4);
  r.mesh.tets.row(m) << int(n), int(n + 1), int(n + 2), int(n + 3);
  const std::string msg = PrecomputeError(r);
  EXPECT_NE(msg.find("attached to no constrained node"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1 cells"), std::string::npos) << msg;
  EXPECT_NE(msg.find("[500, 501]"), std::string::npos) << msg;
}

TEST(InvalidInput, MovableNotConstrainedAndOutOfRangeIds) {
  PrecomputeRequest r = ShellRequest(2, 1);
  r.sets.movable.push_back(r.sets.kept.front());
  EXPECT_NE(PrecomputeError(r).find("is not a constrained node"), std::string::npos);
  PrecomputeRequest r2 = ShellRequest(2, 1);
  r2.sets.kept.push_back(static_cast<int>(r2.mesh.numPoints()) + 3);
  EXPECT_NE(PrecomputeError(r2).find("out of range"), std::string::npos);
}

TEST(InvalidInput, BadSolveInputs) {
  PrecomputeRequest r = ShellRequest(2, 1);
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(r, system).ok);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(r);
  input.movableDisplacement(0, 0) = std::nan("");
  SolveResult result;
  Status s = Solve(*system, input, result);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("NaN"), std::string::npos);
  input.movableDisplacement = RowVectors3d::Zero(3, 3);
  s = Solve(*system, input, result);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("ROI displacements"), std::string::npos);
}
