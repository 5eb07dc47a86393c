// SPDX-License-Identifier: BSD-3-Clause
// The large-deformation solve against the analytic neo-Hookean uniaxial state, a rigid rotation
// (exact, where a linear model distorts), the linear model for small moves, the largest strain
// against every cell's, and bad input.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/LargeDeformation.h"
#include "CondensedFEM/LargeDeformationProblem.h"
#include "Element/NeoHookeanTet.h"
#include "Support/BoxMeshGenerator.h"
#include "Support/FEMTestScenes.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <functional>
#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

constexpr double kLx = 20.0, kLy = 16.0, kLz = 12.0, kNu = 0.45, kE = 3000.0;

// The input that moves the movable nodes by `moves` (one row each) and recovers every node.
SolveInput MovesInput(const std::vector<Eigen::RowVector3d>& moves) {
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(moves.size()), 3);
  for (size_t k = 0; k < moves.size(); ++k)
    input.movableDisplacement.row(static_cast<Eigen::Index>(k)) = moves[k];
  input.recoverInterior = true;
  return input;
}

// Lateral stretch of the homogeneous uniaxial state F = diag(s, s, axial): the s at which the
// lateral stress P_11 vanishes (bisection; P_11 increases with s).
double LateralStretch(double axial, const NeoHookeanParameters& p) {
  double lo = 0.5, hi = 3.0;
  for (int it = 0; it < 200; ++it) {
    const double s = 0.5 * (lo + hi);
    const Eigen::Matrix3d F = Eigen::Vector3d(s, s, axial).asDiagonal();
    (NeoHookeanStress(F, p)(0, 0) > 0.0 ? hi : lo) = s;
  }
  return 0.5 * (lo + hi);
}

TEST(LargeDeformation, PressedBlockIsTheAnalyticUniaxialState) {
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  const double press = 0.35 * kLz; // 35 % compression
  SolveResult result;
  LargeDeformationReport report;
  const Status s = SolveLargeDeformation(request, PlateMove(request, press), {}, result, report);
  ASSERT_TRUE(s.ok) << s.message;
  const double axial = 1.0 - press / kLz;
  const double lateral = LateralStretch(axial, NeoHookeanFromLinear(kE, kNu));
  RowVectors3d exact(request.mesh.numPoints(), 3);
  for (Eigen::Index i = 0; i < exact.rows(); ++i)
    exact.row(i) = request.mesh.points.row(i).cwiseProduct(
        Eigen::RowVector3d(lateral - 1.0, lateral - 1.0, axial - 1.0));
  EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, exact), 1e-8);
  EXPECT_LT(result.relativeResidual, 1e-9);
  // The linear model's lateral expansion, nu * 35 %, is far from it: the test tells them apart.
  EXPECT_GT(std::abs((lateral - 1.0) - kNu * press / kLz), 0.02);
  EXPECT_NEAR(report.smallestVolumeRatio, lateral * lateral * axial, 1e-8);
}

TEST(LargeDeformation, RigidRotationOfAClampedFaceIsExact) {
  // A bar whose end face x = 0 is turned by 90 degrees about the bar's axis: the whole bar turns
  // with it, stress-free. A linear model would shrink and distort it.
  PrecomputeRequest request;
  request.mesh = MakeBoxTetMesh(6, 3, 3, 30.0, 10.0, 10.0);
  request.materials = Materials::Uniform(kE, kNu);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::RowVector3d centre(0.0, 5.0, 5.0);
  RowVectors3d rigid(request.mesh.numPoints(), 3);
  std::vector<Eigen::RowVector3d> moves;
  for (Eigen::Index i = 0; i < request.mesh.numPoints(); ++i) {
    const Eigen::RowVector3d x = request.mesh.points.row(i) - centre;
    rigid.row(i) = (R * x.transpose() - x.transpose()).transpose();
    request.sets.kept.push_back(static_cast<int>(i));
    if (request.mesh.points(i, 0) == 0.0) {
      request.sets.constrained.push_back(static_cast<int>(i));
      request.sets.movable.push_back(static_cast<int>(i));
      moves.push_back(rigid.row(i));
    }
  }
  SolveResult result;
  LargeDeformationReport report;
  const Status s = SolveLargeDeformation(request, MovesInput(moves), {}, result, report);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, rigid), 1e-8);
  EXPECT_LT(report.largestGreenStrain, 1e-8);
  EXPECT_NEAR(report.smallestVolumeRatio, 1.0, 1e-8);
}

TEST(LargeDeformation, SmallMovesAgreeWithTheLinearModel) {
  // The difference to the linear solution is second order in the move: relative to the move it
  // halves when the move halves, and it is small for a small move. With sliding nodes, ties and
  // a kept subset, on the shell scene and the pressed block.
  for (int scene = 0; scene < 2; ++scene) {
    const PrecomputeRequest request =
        scene == 0 ? ShellRequest(4, 2, kE, kNu) : PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
    std::shared_ptr<const CondensedSystem> system;
    Status s = Precompute(request, system);
    ASSERT_TRUE(s.ok) << s.message;
    double previous = 0.0;
    for (double amplitude : {0.02, 0.01}) {
      SolveInput input = scene == 0 ? SolveInput() : PlateMove(request, amplitude);
      if (scene == 0) {
        input.movableDisplacement = SmoothRoiField(request, amplitude);
        input.recoverInterior = true;
      }
      SolveResult linear, large;
      LargeDeformationReport report;
      s = Solve(*system, input, linear);
      ASSERT_TRUE(s.ok) << s.message;
      s = SolveLargeDeformation(request, input, {}, large, report);
      ASSERT_TRUE(s.ok) << s.message;
      const double difference =
          RelativeMaxNodeDifference(large.allDisplacement, linear.allDisplacement);
      EXPECT_LT(difference, 0.01) << "scene " << scene << ", amplitude " << amplitude;
      if (previous > 0.0) {
        EXPECT_GT(previous / difference, 1.6) << "scene " << scene;
        EXPECT_LT(previous / difference, 2.4) << "scene " << scene;
      }
      previous = difference;
      EXPECT_EQ(large.keptDisplacement.rows(), linear.keptDisplacement.rows());
    }
  }
}

TEST(LargeDeformation, TinyMovesConvergeToTheLinearSolution) {
  // At strains of 1e-9 the stress's round-off is far above 1e-9 of the internal force: the solve
  // must still converge (against its round-off floor) and give the linear answer.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  for (double press : {1e-6, 1e-9, 1e-12}) {
    const SolveInput input = PlateMove(request, press * kLz);
    SolveResult linear, large;
    LargeDeformationReport report;
    ASSERT_TRUE(Solve(*system, input, linear).ok);
    const Status s = SolveLargeDeformation(request, input, {}, large, report);
    ASSERT_TRUE(s.ok) << press << ": " << s.message;
    EXPECT_LT(RelativeMaxNodeDifference(large.allDisplacement, linear.allDisplacement), 1e-5)
        << press;
  }
}

TEST(LargeDeformation, CellsNearRestKeepTheirRestTangent) {
  // Half a block moved: the cells whose corners all stay put are at rest (F = I), the others are
  // deformed. With NearRestTangents the cells at rest take the rest tangent and the others their
  // own, the forces are the plain evaluation's, and a cell whose buffer already holds its rest
  // tangent is not copied again.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  large_deformation::Structure st;
  ASSERT_TRUE(large_deformation::MakeStructure(request, false, st).ok);
  const Eigen::Index n = request.mesh.numPoints();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::RowVector3d p = request.mesh.points.row(i);
    if (p.x() > 0.5 * kLx)
      u.segment<3>(3 * i) =
          st.toLocal(static_cast<int>(i), Eigen::Vector3d(0.02 * p.z(), 0.0, -0.05 * p.x()));
  }
  large_deformation::Evaluation atRest, exact, mixed;
  std::vector<double> restPacked, exactPacked, packed;
  ASSERT_TRUE(large_deformation::Evaluate(st, Eigen::VectorXd::Zero(3 * n), atRest, &restPacked));
  ASSERT_TRUE(large_deformation::Evaluate(st, u, exact, &exactPacked));
  std::vector<char> held;
  large_deformation::NearRestTangents nearRest{&restPacked, &held, 1e-9};
  ASSERT_TRUE(large_deformation::Evaluate(st, u, mixed, &packed, nullptr, &nearRest));
  EXPECT_LT((mixed.force - exact.force).norm(), 1e-12 * exact.force.norm());
  EXPECT_NEAR(mixed.energy, exact.energy, 1e-12 * std::abs(exact.energy));
  const Eigen::Index m = request.mesh.numTets();
  ASSERT_EQ(held.size(), static_cast<size_t>(m));
  int atRestCells = 0, deformedCells = 0;
  for (Eigen::Index e = 0; e < m; ++e) {
    bool still = true;
    for (int a = 0; a < 4; ++a)
      still = still && u.segment<3>(3 * st.mesh->tets(e, a)).isZero();
    const size_t at = static_cast<size_t>(e) * kPackedElementSize;
    const std::vector<double>& expected = still ? restPacked : exactPacked;
    double largest = 0.0, difference = 0.0;
    for (int k = 0; k < kPackedElementSize; ++k) {
      largest = std::max(largest, std::abs(expected[at + k]));
      difference = std::max(difference, std::abs(packed[at + k] - expected[at + k]));
    }
    ASSERT_LE(difference, 1e-12 * largest) << "cell " << e << (still ? " at rest" : " deformed");
    EXPECT_EQ(held[static_cast<size_t>(e)], still ? 1 : 0) << e;
    (still ? atRestCells : deformedCells) += 1;
  }
  EXPECT_GT(atRestCells, 0);
  EXPECT_GT(deformedCells, 0);
  // Held flags are trusted: a cell at rest whose buffer is marked as holding its rest tangent is
  // left as it is.
  Eigen::Index restCell = 0;
  while (held[static_cast<size_t>(restCell)] == 0)
    ++restCell;
  packed[static_cast<size_t>(restCell) * kPackedElementSize] = -7.0;
  ASSERT_TRUE(large_deformation::Evaluate(st, u, mixed, &packed, nullptr, &nearRest));
  EXPECT_EQ(packed[static_cast<size_t>(restCell) * kPackedElementSize], -7.0);
  held[static_cast<size_t>(restCell)] = 0;
  ASSERT_TRUE(large_deformation::Evaluate(st, u, mixed, &packed, nullptr, &nearRest));
  EXPECT_EQ(packed[static_cast<size_t>(restCell) * kPackedElementSize],
            restPacked[static_cast<size_t>(restCell) * kPackedElementSize]);
}

TEST(LargeDeformation, BadInputIsAnError) {
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  SolveResult result;
  LargeDeformationReport report;
  SolveInput input = PlateMove(request, 1.0);
  input.movableDisplacement(0, 2) = std::nan("");
  EXPECT_FALSE(SolveLargeDeformation(request, input, {}, result, report).ok);
  input = PlateMove(request, 1.0);
  input.movableDisplacement.conservativeResize(3, 3);
  EXPECT_FALSE(SolveLargeDeformation(request, input, {}, result, report).ok);
  PrecomputeRequest quadratic = request;
  quadratic.options.elementOrder = ElementOrder::Quadratic;
  const Status s = SolveLargeDeformation(quadratic, PlateMove(request, 1.0), {}, result, report);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("linear (4-node) elements"), std::string::npos) << s.message;
  LargeDeformationOptions options;
  options.tolerance = 0.0;
  EXPECT_FALSE(SolveLargeDeformation(request, PlateMove(request, 1.0), options, result, report).ok);
}

TEST(LargeDeformation, TheIterationBoundIsAClearError) {
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  LargeDeformationOptions options;
  options.maxTotalIterations = 1; // the 35 % press needs several
  SolveResult result;
  LargeDeformationReport report;
  const Status s =
      SolveLargeDeformation(request, PlateMove(request, 0.35 * kLz), options, result, report);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("within 1 Newton iterations"), std::string::npos) << s.message;
}

TEST(LargeDeformation, AMoveThatMustInvertCellsIsAClearError) {
  // The plate pushed 1.5 block heights down: no state without inverted cells reaches it.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  SolveResult result;
  LargeDeformationReport report;
  const Status s =
      SolveLargeDeformation(request, PlateMove(request, 1.5 * kLz), {}, result, report);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("did not converge"), std::string::npos) << s.message;
  EXPECT_GT(report.rejectedSteps, 0);
}

} // namespace

namespace {

// A block on a frictionless floor (z = 0, sliding with the given normal) whose top face
// (z = kLz) is held and moved by `top(x)`; the sides are free.
struct FloorBlock {
  PrecomputeRequest request;
  SolveInput input;
  std::vector<int> floor; // node ids on the floor
};
FloorBlock BlockOnFloor(const Eigen::Vector3d& floorNormal,
                        const std::function<Eigen::RowVector3d(const Eigen::RowVector3d&)>& top) {
  FloorBlock b;
  b.request.mesh = MakeBoxTetMesh(4, 4, 3, kLx, kLx, kLz);
  b.request.materials = Materials::Uniform(kE, kNu);
  std::vector<Eigen::RowVector3d> moves;
  for (Eigen::Index i = 0; i < b.request.mesh.numPoints(); ++i) {
    const Eigen::RowVector3d p = b.request.mesh.points.row(i);
    const int node = static_cast<int>(i);
    b.request.sets.kept.push_back(node);
    if (p.z() == 0.0) {
      b.request.sets.constrained.push_back(node);
      b.request.sets.sliding.push_back(node);
      b.request.sets.slidingNormal.push_back(floorNormal);
      b.floor.push_back(node);
    } else if (p.z() == kLz) {
      b.request.sets.constrained.push_back(node);
      b.request.sets.movable.push_back(node);
      moves.push_back(top(p));
    }
  }
  b.input.movableDisplacement.resize(static_cast<Eigen::Index>(moves.size()), 3);
  for (size_t k = 0; k < moves.size(); ++k)
    b.input.movableDisplacement.row(static_cast<Eigen::Index>(k)) = moves[k];
  b.input.recoverInterior = true;
  return b;
}

LargeDeformationOptions LiftOff() {
  LargeDeformationOptions o;
  o.slidingLiftOff = true;
  return o;
}

TEST(LargeDeformation, LiftOffLetsABlockPulledUpLeaveTheFloor) {
  // Whichever way the floor's normal is given, the tissue side decides: pulled up, the block
  // leaves the floor as one rigid body; held both ways (no lift-off) it stretches.
  for (double sign : {1.0, -1.0}) {
    FloorBlock b = BlockOnFloor(sign * Eigen::Vector3d::UnitZ(), [](const Eigen::RowVector3d&) {
      return Eigen::RowVector3d(0, 0, 3.0);
    });
    SolveResult lifted, held;
    LargeDeformationReport liftedReport, heldReport;
    Status s = SolveLargeDeformation(b.request, b.input, LiftOff(), lifted, liftedReport);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(liftedReport.liftedNodes, static_cast<int>(b.floor.size()));
    RowVectors3d rigid = RowVectors3d::Zero(b.request.mesh.numPoints(), 3);
    rigid.col(2).setConstant(3.0);
    EXPECT_LT(RelativeMaxNodeDifference(lifted.allDisplacement, rigid), 1e-8) << sign;
    s = SolveLargeDeformation(b.request, b.input, {}, held, heldReport);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(heldReport.liftedNodes, 0);
    EXPECT_GT(heldReport.largestGreenStrain, 0.1);
    for (int node : b.floor)
      EXPECT_NEAR(held.allDisplacement(node, 2), 0.0, 1e-12);
  }
}

TEST(LargeDeformation, LiftOffKeepsAPressedBlockOnTheFloor) {
  FloorBlock b = BlockOnFloor(Eigen::Vector3d::UnitZ(), [](const Eigen::RowVector3d&) {
    return Eigen::RowVector3d(0, 0, -3.0);
  });
  SolveResult lifted, held;
  LargeDeformationReport liftedReport, heldReport;
  ASSERT_TRUE(SolveLargeDeformation(b.request, b.input, LiftOff(), lifted, liftedReport).ok);
  ASSERT_TRUE(SolveLargeDeformation(b.request, b.input, {}, held, heldReport).ok);
  EXPECT_EQ(liftedReport.liftedNodes, 0);
  EXPECT_LT(RelativeMaxNodeDifference(lifted.allDisplacement, held.allDisplacement), 1e-10);
}

TEST(LargeDeformation, LiftOffSettlesAMixedContact) {
  // The top face tilted about its centre line: one half of the floor is pressed, the other half
  // pulled. The result is the unilateral solution: floor nodes either on the floor or above it,
  // some of each, and the pressed side's floor nodes stay down.
  const double angle = 0.25;
  FloorBlock b = BlockOnFloor(Eigen::Vector3d::UnitZ(), [angle](const Eigen::RowVector3d& p) {
    const double x = p.x() - 0.5 * kLx;
    return Eigen::RowVector3d(x * (std::cos(angle) - 1.0), 0.0, x * std::sin(angle));
  });
  SolveResult result;
  LargeDeformationReport report;
  const Status s = SolveLargeDeformation(b.request, b.input, LiftOff(), result, report);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_GT(report.liftedNodes, 0);
  EXPECT_LT(report.liftedNodes, static_cast<int>(b.floor.size()));
  int above = 0;
  for (int node : b.floor) {
    const double z = result.allDisplacement(node, 2);
    EXPECT_GT(z, -1e-10) << "floor node " << node << " went into the floor";
    above += z > 1e-8 ? 1 : 0;
    if (b.request.mesh.points(node, 0) == 0.0)
      EXPECT_NEAR(z, 0.0, 1e-10) << "the pressed edge stays down";
  }
  EXPECT_EQ(above, report.liftedNodes);
}

} // namespace

// The largest principal strain over the cells and its cell, from every cell's eigenvalues.
std::pair<double, long long> LargestStrainOfEveryCell(const PrecomputeRequest& request,
                                                      const RowVectors3d& displacement,
                                                      double* smallest = nullptr) {
  double largest = 0.0;
  long long cell = -1;
  for (Eigen::Index e = 0; e < request.mesh.numTets(); ++e) {
    TetCorners corners;
    CornerDisplacements u;
    for (int a = 0; a < 4; ++a) {
      corners.row(a) = request.mesh.points.row(request.mesh.tets(e, a));
      u.row(a) = displacement.row(request.mesh.tets(e, a));
    }
    const Eigen::Matrix3d F = DeformationGradient(MakeTetReference(corners), u);
    const Eigen::Matrix3d green = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(green, Eigen::EigenvaluesOnly);
    const double strain = eigen.eigenvalues().cwiseAbs().maxCoeff();
    if (smallest)
      *smallest = e == 0 ? strain : std::min(*smallest, strain);
    if (strain > largest) {
      largest = strain;
      cell = e;
    }
  }
  return {largest, cell};
}

TEST(LargeDeformation, TheLargestStrainIsTheLargestOfEveryCell) {
  // The reported largest principal strain and its cell are those of a scan that solves every
  // cell's eigenvalues (the measure skips the cells whose strain's norm cannot beat the largest
  // so far). A bar whose end face is turned by 40 degrees and pushed in strains its cells
  // unequally; the pressed block strains them equally but for round-off, so that a skip of a
  // cell that could beat the largest would name another cell.
  PrecomputeRequest request;
  request.mesh = MakeBoxTetMesh(12, 4, 4, 30.0, 10.0, 10.0);
  request.materials = Materials::Uniform(kE, kNu);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(40.0 / 180.0 * M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::RowVector3d centre(0.0, 5.0, 5.0);
  std::vector<Eigen::RowVector3d> moves;
  for (Eigen::Index i = 0; i < request.mesh.numPoints(); ++i) {
    request.sets.kept.push_back(static_cast<int>(i));
    const Eigen::RowVector3d x = request.mesh.points.row(i);
    if (x(0) == 0.0 || x(0) == 30.0) {
      request.sets.constrained.push_back(static_cast<int>(i));
      if (x(0) == 0.0) {
        request.sets.movable.push_back(static_cast<int>(i));
        const Eigen::Vector3d local = (x - centre).transpose();
        moves.push_back((R * local - local).transpose() + Eigen::RowVector3d(4.0, 6.0, 0.0));
      }
    }
  }
  SolveResult result;
  LargeDeformationReport report;
  Status s = SolveLargeDeformation(request, MovesInput(moves), {}, result, report);
  ASSERT_TRUE(s.ok) << s.message;
  double smallest = 0.0;
  const auto [largest, cell] = LargestStrainOfEveryCell(request, result.allDisplacement, &smallest);
  EXPECT_LT(smallest, 0.5 * largest) << "the cells must strain unequally for the test to tell";
  EXPECT_EQ(report.largestGreenStrain, largest);
  EXPECT_EQ(report.largestStrainCell, cell);
  EXPECT_EQ(result.largestStrain, largest);

  const PrecomputeRequest block = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  s = SolveLargeDeformation(block, PlateMove(block, 0.2 * kLz), {}, result, report);
  ASSERT_TRUE(s.ok) << s.message;
  const auto [blockLargest, blockCell] = LargestStrainOfEveryCell(block, result.allDisplacement);
  EXPECT_EQ(report.largestGreenStrain, blockLargest);
  EXPECT_EQ(report.largestStrainCell, blockCell);
}
