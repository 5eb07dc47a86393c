// The large-deformation solve against the analytic neo-Hookean uniaxial state, a rigid rotation
// (exact, where a linear model distorts), the linear model for small moves, and bad input.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/LargeDeformation.h"
#include "Element/NeoHookeanTet.h"
#include "Support/BoxMeshGenerator.h"
#include "Support/FEMTestScenes.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

constexpr double kLx = 20.0, kLy = 16.0, kLz = 12.0, kNu = 0.45, kE = 3000.0;

SolveInput PlateMove(const PrecomputeRequest& request, double press) {
  SolveInput input;
  input.movableDisplacement =
      RowVectors3d::Zero(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  input.movableDisplacement.col(2).setConstant(-press);
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
  SolveInput input;
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
  input.movableDisplacement.resize(static_cast<Eigen::Index>(moves.size()), 3);
  for (size_t k = 0; k < moves.size(); ++k)
    input.movableDisplacement.row(static_cast<Eigen::Index>(k)) = moves[k];
  input.recoverInterior = true;
  SolveResult result;
  LargeDeformationReport report;
  const Status s = SolveLargeDeformation(request, input, {}, result, report);
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
