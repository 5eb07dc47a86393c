// SPDX-License-Identifier: BSD-3-Clause
// The precomputed large-deformation solve against Newton's (the same equilibrium to 1e-8), warm
// starts against cold solves, lift-off's active set changing during a drag, a move that must invert
// cells, the fallback to Newton, the background refactorization and bad input.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/LargeDeformation.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"
#include "Support/BoxMeshGenerator.h"
#include "Support/FEMTestScenes.h"
#include "Support/PrecomputedSystem.h"

#include <cmath>
#include <functional>
#include <gtest/gtest.h>

#include <string>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

constexpr double kLx = 20.0, kLy = 16.0, kLz = 12.0, kNu = 0.45, kE = 3000.0;
constexpr double kAgreement = 1e-8;

// A block on a frictionless floor (z = 0, sliding) whose top face is held and moved by `top`.
struct FloorBlock {
  PrecomputeRequest request;
  std::vector<int> floor;
  std::vector<Eigen::RowVector3d> topPoints;
  SolveInput input(const std::function<Eigen::RowVector3d(const Eigen::RowVector3d&)>& top) const {
    SolveInput in;
    in.movableDisplacement.resize(static_cast<Eigen::Index>(topPoints.size()), 3);
    for (size_t k = 0; k < topPoints.size(); ++k)
      in.movableDisplacement.row(static_cast<Eigen::Index>(k)) = top(topPoints[k]);
    in.recoverInterior = true;
    return in;
  }
};
FloorBlock BlockOnFloor() {
  FloorBlock b;
  b.request.mesh = MakeBoxTetMesh(4, 4, 3, kLx, kLx, kLz);
  b.request.materials = Materials::Uniform(kE, kNu);
  for (Eigen::Index i = 0; i < b.request.mesh.numPoints(); ++i) {
    const Eigen::RowVector3d p = b.request.mesh.points.row(i);
    const int node = static_cast<int>(i);
    b.request.sets.kept.push_back(node);
    if (p.z() == 0.0) {
      b.request.sets.constrained.push_back(node);
      b.request.sets.sliding.push_back(node);
      b.request.sets.slidingNormal.push_back(Eigen::Vector3d::UnitZ());
      b.floor.push_back(node);
    } else if (p.z() == kLz) {
      b.request.sets.constrained.push_back(node);
      b.request.sets.movable.push_back(node);
      b.topPoints.push_back(p);
    }
  }
  return b;
}

// The top face tilted by `angle` about its centre line: one side presses, the other pulls.
std::function<Eigen::RowVector3d(const Eigen::RowVector3d&)> Tilt(double angle) {
  return [angle](const Eigen::RowVector3d& p) {
    const double x = p.x() - 0.5 * kLx;
    return Eigen::RowVector3d(x * (std::cos(angle) - 1.0), 0.0, x * std::sin(angle));
  };
}

// One step of a drag whose refactorization is awaited: the warm solve from `state` (advanced to its
// result) and, on `coldSystem` (a system of its own, whose refactorizations cannot replace the
// drag's), the cold solve of the same input, which the warm one must equal. Their reports go to
// `warm` and `cold`.
void AwaitedDragStep(LargeDeformationSystem& system, LargeDeformationSystem& coldSystem,
                     const SolveInput& input, LargeDeformationState& state,
                     PrecomputedLargeDeformationReport& warm,
                     PrecomputedLargeDeformationReport& cold) {
  SolveResult warmResult, coldResult;
  LargeDeformationState next;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(system, input, &state, warmResult, warm, &next).ok);
  EXPECT_FALSE(warm.fellBack) << warm.fallbackReason;
  WaitForRefactorization(system);
  state = next;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(coldSystem, input, nullptr, coldResult, cold).ok);
  EXPECT_LT(RelativeMaxNodeDifference(warmResult.allDisplacement, coldResult.allDisplacement),
            kAgreement);
}

// The precomputed solve with lift-off's unilateral contact, the other options their defaults.
PrecomputedLargeDeformationOptions LiftOffOptions() {
  PrecomputedLargeDeformationOptions options;
  options.slidingLiftOff = true;
  return options;
}

SolveResult Newton(const PrecomputeRequest& request, const SolveInput& input, bool liftOff,
                   LargeDeformationReport* out = nullptr) {
  LargeDeformationOptions options;
  options.slidingLiftOff = liftOff;
  SolveResult result;
  LargeDeformationReport report;
  const Status s = SolveLargeDeformation(request, input, options, result, report);
  EXPECT_TRUE(s.ok) << s.message;
  if (out)
    *out = report;
  return result;
}

TEST(PrecomputedLargeDeformation, SmallStrainCellsAreTheLinearModel) {
  // Cells flagged small-strain (LipSeal's bridges) are linear elastic under both large-deformation
  // solvers: with every cell flagged, the shell's 5 mm push is the linear model's answer, where the
  // neo-Hookean cells' answer differs from it at first order.
  PrecomputeRequest request = ShellRequest(4, 2);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request, 5.0);
  input.recoverInterior = true;
  std::shared_ptr<const CondensedSystem> linearSystem;
  ASSERT_TRUE(Precompute(request, linearSystem).ok);
  SolveResult linear;
  ASSERT_TRUE(Solve(*linearSystem, input, linear).ok);
  const SolveResult neoHookean = Newton(request, input, false);
  EXPECT_GT(RelativeMaxNodeDifference(neoHookean.allDisplacement, linear.allDisplacement), 1e-3);

  request.materials.smallStrain.assign(static_cast<size_t>(request.mesh.numTets()), 1);
  LargeDeformationReport newtonReport;
  const SolveResult newton = Newton(request, input, false, &newtonReport);
  EXPECT_LT(RelativeMaxNodeDifference(newton.allDisplacement, linear.allDisplacement), kAgreement);
  auto system = Precomputed(request);
  ASSERT_TRUE(system);
  SolveResult precomputed;
  PrecomputedLargeDeformationReport report;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, nullptr, precomputed, report).ok);
  EXPECT_FALSE(report.fellBack) << report.fallbackReason;
  EXPECT_LT(RelativeMaxNodeDifference(precomputed.allDisplacement, linear.allDisplacement),
            kAgreement);
  // Its initial Hessian is the exact (constant) tangent: the predictor is the answer.
  EXPECT_LE(report.iterations, 1);
}

TEST(PrecomputedLargeDeformation, AgreesWithNewton) {
  // A 35 % press (no sliding), the shell's 5 mm ROI push with ties and sliding nodes and a kept
  // subset, and the sliding shell on a curved surface.
  std::vector<std::pair<PrecomputeRequest, SolveInput>> scenes;
  {
    const PrecomputeRequest r = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
    scenes.emplace_back(r, PlateMove(r, 0.35 * kLz));
  }
  {
    const PrecomputeRequest r = ShellRequest(4, 2);
    SolveInput in;
    in.movableDisplacement = SmoothRoiField(r, 5.0);
    scenes.emplace_back(r, in);
  }
  {
    RowVectors3d moves;
    const PrecomputeRequest r = SlidingShellRequest(10.0, moves);
    SolveInput in;
    in.movableDisplacement = moves;
    scenes.emplace_back(r, in);
  }
  for (size_t k = 0; k < scenes.size(); ++k) {
    const auto& [request, input] = scenes[k];
    auto system = Precomputed(request);
    ASSERT_TRUE(system);
    SolveResult result;
    PrecomputedLargeDeformationReport report;
    const Status s = SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_FALSE(report.fellBack) << "scene " << k << ": " << report.fallbackReason;
    EXPECT_EQ(result.method, SolveMethod::LargeDeformationPrecomputed);
    EXPECT_LT(result.relativeResidual, 1e-9);
    const SolveResult newton = Newton(request, input, false);
    EXPECT_LT(RelativeMaxNodeDifference(result.keptDisplacement, newton.keptDisplacement),
              kAgreement)
        << "scene " << k;
    EXPECT_EQ(newton.method, SolveMethod::LargeDeformationNewton);
    EXPECT_GT(report.largestGreenStrain, 0.1) << "scene " << k << " is a large move";
  }
}

TEST(PrecomputedLargeDeformation, LiftOffAgreesWithNewton) {
  // Pulled up, the block leaves the floor; tilted, part of it does: the constrained equilibrium.
  const FloorBlock b = BlockOnFloor();
  auto system = Precomputed(b.request, LiftOffOptions());
  ASSERT_TRUE(system);
  for (const auto& top :
       {Tilt(0.25), std::function<Eigen::RowVector3d(const Eigen::RowVector3d&)>(
                        [](const Eigen::RowVector3d&) { return Eigen::RowVector3d(0, 0, 3.0); })}) {
    const SolveInput input = b.input(top);
    SolveResult result;
    PrecomputedLargeDeformationReport report;
    const Status s = SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_FALSE(report.fellBack) << report.fallbackReason;
    LargeDeformationReport newtonReport;
    const SolveResult newton = Newton(b.request, input, true, &newtonReport);
    EXPECT_EQ(report.liftedNodes, newtonReport.liftedNodes);
    EXPECT_GT(report.liftedNodes, 0);
    EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, newton.allDisplacement),
              kAgreement);
  }
}

TEST(PrecomputedLargeDeformation, WarmStartsEqualColdSolvesAndTheActiveSetChangesInADrag) {
  // The tilt dragged from 0 in small steps, each step warm-started from the last: at first every
  // floor node stays down, then more and more lift off. Each step equals a cold solve and Newton.
  const FloorBlock b = BlockOnFloor();
  auto system = Precomputed(b.request, LiftOffOptions());
  ASSERT_TRUE(system);
  LargeDeformationState state;
  std::vector<int> lifted;
  for (int step = 1; step <= 6; ++step) {
    const SolveInput input = b.input(Tilt(0.05 * step));
    SolveResult warm, cold;
    PrecomputedLargeDeformationReport warmReport, coldReport;
    LargeDeformationState next;
    Status s = SolvePrecomputedLargeDeformation(*system, input, &state, warm, warmReport, &next);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(warmReport.warmStarted, step > 1);
    EXPECT_FALSE(warmReport.fellBack) << warmReport.fallbackReason;
    state = next;
    ASSERT_TRUE(state.valid());
    s = SolvePrecomputedLargeDeformation(*system, input, nullptr, cold, coldReport);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_FALSE(coldReport.warmStarted);
    EXPECT_LT(RelativeMaxNodeDifference(warm.allDisplacement, cold.allDisplacement), kAgreement)
        << "step " << step;
    LargeDeformationReport newtonReport;
    const SolveResult newton = Newton(b.request, input, true, &newtonReport);
    EXPECT_LT(RelativeMaxNodeDifference(warm.allDisplacement, newton.allDisplacement), kAgreement)
        << "step " << step;
    EXPECT_EQ(warmReport.liftedNodes, newtonReport.liftedNodes) << "step " << step;
    lifted.push_back(warmReport.liftedNodes);
  }
  EXPECT_LT(lifted.front(), lifted.back()) << "the active set changed during the drag";
  WaitForRefactorization(*system);
  EXPECT_GT(BackgroundRefactorizations(*system), 0);
}

// An update that changes nothing the solve reads (the same targets and loads, warm-started from
// their converged state) returns that state as it is, with no iteration: a step from it would move
// it within the tolerance, and the same input would give another result each time.
TEST(PrecomputedLargeDeformation, AnUnchangedInputReturnsItsConvergedState) {
  const FloorBlock b = BlockOnFloor();
  auto system = Precomputed(b.request, LiftOffOptions());
  ASSERT_TRUE(system);
  const SolveInput input = b.input(Tilt(0.2));
  SolveResult first, again;
  PrecomputedLargeDeformationReport firstReport, againReport;
  LargeDeformationState state, next;
  ASSERT_TRUE(
      SolvePrecomputedLargeDeformation(*system, input, nullptr, first, firstReport, &state).ok);
  ASSERT_GT(firstReport.iterations, 0);
  ASSERT_GT(firstReport.liftedNodes, 0) << "a state with lift-off's contact";
  WaitForRefactorization(*system); // the factor of the converged state, as after a pause
  for (int repeat = 0; repeat < 2; ++repeat) {
    ASSERT_TRUE(
        SolvePrecomputedLargeDeformation(*system, input, &state, again, againReport, &next).ok);
    EXPECT_TRUE(againReport.warmStarted);
    EXPECT_EQ(againReport.iterations, 0);
    EXPECT_TRUE(again.allDisplacement == first.allDisplacement) << "repeat " << repeat;
    state = next;
  }
}

// The block pressed onto the floor, then tilted more and more, step after step with each
// refactorization awaited: the floor unloads row by row from one side, so nodes lift off on the
// way. Every step equals the cold solve. Sums the iterations and contact updates of the steps
// after the first (the drag's, from a factor made for it) and counts the steps that lifted nodes.
struct TiltDrag {
  int iterations = 0, contactUpdates = 0, releasingSteps = 0;
};
void DragTheTilt(const PrecomputedLargeDeformationOptions& options, TiltDrag& out) {
  const FloorBlock b = BlockOnFloor();
  PrecomputedLargeDeformationOptions coldOptions = LiftOffOptions();
  coldOptions.backgroundRefactorization = false;
  auto coldSystem = Precomputed(b.request, coldOptions);
  ASSERT_TRUE(coldSystem);
  auto system = Precomputed(b.request, options);
  ASSERT_TRUE(system);
  LargeDeformationState state;
  int lastLifted = 0;
  for (int step = 1; step <= 10; ++step) {
    const double angle = 0.03 * step;
    const SolveInput input = b.input([angle](const Eigen::RowVector3d& p) {
      const double x = p.x() - 0.5 * kLx;
      return Eigen::RowVector3d(x * (std::cos(angle) - 1.0), 0.0, x * std::sin(angle) - 0.1 * kLz);
    });
    SCOPED_TRACE("step " + std::to_string(step));
    PrecomputedLargeDeformationReport report, coldReport;
    ASSERT_NO_FATAL_FAILURE(
        AwaitedDragStep(*system, *coldSystem, input, state, report, coldReport));
    EXPECT_EQ(report.liftedNodes, coldReport.liftedNodes);
    if (step > 1) {
      out.iterations += report.iterations;
      out.contactUpdates += report.contactUpdates;
      if (report.liftedNodes > lastLifted)
        ++out.releasingSteps;
    }
    lastLifted = report.liftedNodes;
  }
}

TEST(PrecomputedLargeDeformation, NodesReleasedInADragAreCoupledBackIntoTheInitialHessian) {
  // Without the contact predicted ahead, each release happens inside a step, freeing DOFs that the
  // factor has pinned. Coupled back in through their Schur complement the steps take fewer
  // iterations than with their diagonal alone.
  TiltDrag drag[2];
  for (int coupled = 0; coupled < 2; ++coupled) {
    PrecomputedLargeDeformationOptions options = LiftOffOptions();
    options.predictContactAhead = false;
    options.maxCoupledReleases = coupled ? 8 : 0;
    ASSERT_NO_FATAL_FAILURE(DragTheTilt(options, drag[coupled]));
  }
  EXPECT_GT(drag[1].releasingSteps, 1) << "the drag released nodes on several steps";
  EXPECT_LT(drag[1].iterations, drag[0].iterations)
      << "coupled: " << drag[1].iterations << " iterations, diagonal only: " << drag[0].iterations;
}

TEST(PrecomputedLargeDeformation, AMoveFromRestCouplesEveryNodeItReleases) {
  // Pulled up from rest, the whole floor lifts off: more DOFs than a factor made in a solve couples
  // (none here). The rest factor's coupling of every lift-off DOF couples them all; the solve then
  // takes fewer iterations than with their diagonal alone, and both are Newton's equilibrium. A
  // tilt releases part of the floor, a subset of the coupling's DOFs. With fewer lift-off DOFs
  // allowed than the floor has, there is no coupling: the diagonal's iterations.
  const FloorBlock b = BlockOnFloor();
  for (const auto& top :
       {Tilt(0.25), std::function<Eigen::RowVector3d(const Eigen::RowVector3d&)>(
                        [](const Eigen::RowVector3d&) { return Eigen::RowVector3d(0, 0, 3.0); })}) {
    const SolveInput input = b.input(top);
    LargeDeformationReport newtonReport;
    const SolveResult newton = Newton(b.request, input, true, &newtonReport);
    PrecomputedLargeDeformationReport reports[3];
    for (int coupled = 0; coupled < 3; ++coupled) {
      PrecomputedLargeDeformationOptions options = LiftOffOptions();
      options.maxCoupledReleases = 0;
      options.adaptiveRefactorization = false;
      options.refactorAfter = 0; // the rest factor throughout
      options.coupleRestReleases = coupled >= 1;
      if (coupled == 2)
        options.maxRestReleases = static_cast<int>(b.floor.size()) - 1;
      auto system = Precomputed(b.request, options);
      ASSERT_TRUE(system);
      SolveResult result;
      PrecomputedLargeDeformationReport& report = reports[coupled];
      const Status s = SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report);
      ASSERT_TRUE(s.ok) << s.message;
      EXPECT_FALSE(report.fellBack) << report.fallbackReason;
      EXPECT_EQ(report.refactorizations, 0);
      EXPECT_EQ(report.liftedNodes, newtonReport.liftedNodes);
      EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, newton.allDisplacement),
                kAgreement)
          << "coupled " << coupled;
    }
    EXPECT_GT(reports[1].liftedNodes, 8);
    EXPECT_LT(reports[1].iterations, reports[0].iterations)
        << "coupled: " << reports[1].iterations << ", diagonal only: " << reports[0].iterations;
    EXPECT_EQ(reports[2].iterations, reports[0].iterations) << "too many for the coupling";
  }
}

TEST(PrecomputedLargeDeformation, TheContactPredictedAheadSparesTheDragsContactChanges) {
  // The same drag with the factor made ahead taking the contact predicted there: the nodes that a
  // step lifts off are free in its factor already, so the steps change the contact less often and
  // iterate less, and still equal the cold solve (DragTheTilt).
  TiltDrag drag[2];
  for (int predicted = 0; predicted < 2; ++predicted) {
    PrecomputedLargeDeformationOptions options = LiftOffOptions();
    options.predictContactAhead = predicted == 1;
    ASSERT_NO_FATAL_FAILURE(DragTheTilt(options, drag[predicted]));
  }
  EXPECT_GT(drag[1].releasingSteps, 1) << "the drag released nodes on several steps";
  EXPECT_LT(drag[1].contactUpdates, drag[0].contactUpdates)
      << "predicted: " << drag[1].contactUpdates
      << " contact updates, not predicted: " << drag[0].contactUpdates;
  EXPECT_LT(drag[1].iterations, drag[0].iterations)
      << "predicted: " << drag[1].iterations
      << " iterations, not predicted: " << drag[0].iterations;
}

TEST(PrecomputedLargeDeformation, ADragOnTheShellEqualsTheColdSolve) {
  const PrecomputeRequest request = ShellRequest(4, 2);
  auto system = Precomputed(request);
  ASSERT_TRUE(system);
  LargeDeformationState state;
  SolveInput input;
  input.recoverInterior = true;
  for (double amplitude = 0.5; amplitude <= 5.0; amplitude += 0.5) {
    input.movableDisplacement = SmoothRoiField(request, amplitude);
    SolveResult result;
    PrecomputedLargeDeformationReport report;
    LargeDeformationState next;
    ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, &state, result, report, &next).ok);
    state = next;
  }
  SolveResult warm, cold;
  PrecomputedLargeDeformationReport report;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, &state, warm, report).ok);
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, nullptr, cold, report).ok);
  EXPECT_LT(RelativeMaxNodeDifference(warm.allDisplacement, cold.allDisplacement), kAgreement);
  // A state of another system is not used.
  auto other = Precomputed(request);
  ASSERT_TRUE(other);
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*other, input, &state, warm, report).ok);
  EXPECT_FALSE(report.warmStarted);
}

TEST(PrecomputedLargeDeformation, ADragFactoredOneStepAheadTakesFewerIterations) {
  // The same change of the move, step after step, each refactorization awaited: with the tangent
  // factored where the next step would lead (and the predictor starting there) every step equals
  // the cold solve and the steps after the first take fewer iterations than with the tangent
  // factored at the converged state, fewer again when a steady drag is extrapolated to second
  // order (the parabola through the last three states) rather than along the line, and fewer
  // again when that state is corrected by a Newton step before the tangent is factored there.
  const PrecomputeRequest request = ShellRequest(4, 2);
  PrecomputedLargeDeformationOptions coldOptions;
  coldOptions.backgroundRefactorization = false;
  auto coldSystem = Precomputed(request, coldOptions);
  ASSERT_TRUE(coldSystem);
  int iterations[4] = {0, 0, 0, 0};
  // At the state; ahead, first order; second order; second order, corrected.
  for (int ahead = 0; ahead < 4; ++ahead) {
    PrecomputedLargeDeformationOptions options;
    options.factorAhead = ahead > 0;
    options.factorAheadOrder = ahead == 1 ? 1 : 2;
    options.aheadCorrections = ahead == 3 ? 1 : 0;
    auto system = Precomputed(request, options);
    ASSERT_TRUE(system);
    LargeDeformationState state;
    SolveInput input;
    input.recoverInterior = true;
    for (int step = 0; step < 6; ++step) {
      input.movableDisplacement = SmoothRoiField(request, 3.0 + 0.25 * step);
      SCOPED_TRACE("step " + std::to_string(step) + ", ahead " + std::to_string(ahead));
      PrecomputedLargeDeformationReport report, coldReport;
      ASSERT_NO_FATAL_FAILURE(
          AwaitedDragStep(*system, *coldSystem, input, state, report, coldReport));
      if (step >= 2)
        iterations[ahead] += report.iterations;
    }
  }
  EXPECT_LT(iterations[1], iterations[0])
      << "factored ahead: " << iterations[1] << " iterations, at the state: " << iterations[0];
  EXPECT_LT(iterations[2], iterations[1])
      << "second order: " << iterations[2] << " iterations, first order: " << iterations[1];
  EXPECT_LT(iterations[3], iterations[2])
      << "corrected: " << iterations[3] << " iterations, second order: " << iterations[2];
}

TEST(PrecomputedLargeDeformation, AMoveThatMustInvertCellsIsAClearError) {
  // The plate pushed 1.5 block heights down: no state without inverted cells reaches it. The
  // precomputed solve falls back to Newton, whose load steps cannot go further either.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  auto system = Precomputed(request);
  ASSERT_TRUE(system);
  SolveResult result;
  PrecomputedLargeDeformationReport report;
  const Status s = SolvePrecomputedLargeDeformation(*system, PlateMove(request, 1.5 * kLz), nullptr,
                                                    result, report);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("did not converge"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("a cell would invert"), std::string::npos) << s.message;
  EXPECT_TRUE(report.fellBack);
}

TEST(PrecomputedLargeDeformation, ItFallsBackToNewtonAndSaysSo) {
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  PrecomputedLargeDeformationOptions options;
  options.maxIterations = 1; // the 35 % press needs more
  auto system = Precomputed(request, options);
  ASSERT_TRUE(system);
  const SolveInput input = PlateMove(request, 0.35 * kLz);
  SolveResult result;
  PrecomputedLargeDeformationReport report;
  LargeDeformationState state;
  Status s = SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report, &state);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_TRUE(report.fellBack);
  EXPECT_NE(report.fallbackReason.find("within 1 quasi-Newton iterations"), std::string::npos)
      << report.fallbackReason;
  EXPECT_EQ(result.method, SolveMethod::LargeDeformationNewton);
  EXPECT_GT(report.newton.newtonIterations, 0);
  EXPECT_FALSE(state.valid()) << "no warm state from the fallback";
  const SolveResult newton = Newton(request, input, false);
  EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, newton.allDisplacement), 1e-14);

  // Without the fallback the bound is an error, never an unconverged answer.
  options.fallBackToNewton = false;
  system = Precomputed(request, options);
  ASSERT_TRUE(system);
  s = SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("did not converge"), std::string::npos) << s.message;
}

// A cold solve of `input` on a system precomputed with `options`: converged without a fallback, to
// Newton's equilibrium `newton`. Its report goes to `report`.
void SolveAsNewton(const PrecomputeRequest& request, const SolveInput& input,
                   const PrecomputedLargeDeformationOptions& options, const SolveResult& newton,
                   PrecomputedLargeDeformationReport& report) {
  auto system = Precomputed(request, options);
  ASSERT_TRUE(system);
  SolveResult result;
  const Status s = SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_FALSE(report.fellBack) << report.fallbackReason;
  EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, newton.allDisplacement), kAgreement);
}

TEST(PrecomputedLargeDeformation, ASlowConvergenceRefactorsWhereItIs) {
  // A 55 % press from rest converges slowly with the rest tangent's factor: with adaptive
  // refactorization the solve factors the tangent at its iterate once the last iterations' rate
  // predicts more work than a factorization, and then needs fewer iterations; both are Newton's
  // equilibrium, and a second solve repeats the first bit for bit.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  const SolveInput input = PlateMove(request, 0.55 * kLz);
  const SolveResult newton = Newton(request, input, false);
  PrecomputedLargeDeformationReport reports[2];
  for (int adaptive = 0; adaptive < 2; ++adaptive) {
    PrecomputedLargeDeformationOptions options;
    options.refactorAfter = 0; // only the adaptive rule refactors
    options.adaptiveRefactorization = adaptive == 1;
    SCOPED_TRACE("adaptive " + std::to_string(adaptive));
    SolveAsNewton(request, input, options, newton, reports[adaptive]);
  }
  EXPECT_EQ(reports[0].refactorizations, 0);
  EXPECT_GE(reports[1].refactorizations, 1);
  EXPECT_LT(reports[1].iterations, reports[0].iterations);
  auto system = Precomputed(request);
  ASSERT_TRUE(system);
  SolveResult first, second;
  PrecomputedLargeDeformationReport report;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, nullptr, first, report).ok);
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, nullptr, second, report).ok);
  EXPECT_EQ(RelativeMaxNodeDifference(first.allDisplacement, second.allDisplacement), 0.0);
}

TEST(PrecomputedLargeDeformation, ARefactorizationReusesTheRestFactorWhereTheMoveDoesNotReach) {
  // A long bar on a fixed floor, its top pressed by a third of its height over its first fifth:
  // the tangent at an iterate differs from the rest tangent near the press and barely at the far
  // end. A refactorization then reuses the rest factor's supernodes there (the factor is that of
  // a tangent with the rest values in their columns), and the solve is still Newton's equilibrium;
  // without reuse (a negative tolerance) every factorization is whole.
  constexpr double kLong = 60.0, kPressed = 12.0;
  PrecomputeRequest request;
  request.mesh = MakeBoxTetMesh(15, 3, 3, kLong, kLy, kLz);
  request.materials = Materials::Uniform(kE, kNu);
  for (Eigen::Index i = 0; i < request.mesh.numPoints(); ++i) {
    const Eigen::RowVector3d p = request.mesh.points.row(i);
    const int node = static_cast<int>(i);
    request.sets.kept.push_back(node);
    if (p.z() == 0.0 || (p.z() == kLz && p.x() <= kPressed))
      request.sets.constrained.push_back(node);
    if (p.z() == kLz && p.x() <= kPressed)
      request.sets.movable.push_back(node);
  }
  const SolveInput input = PlateMove(request, kLz / 3.0);
  const SolveResult newton = Newton(request, input, false);
  PrecomputedLargeDeformationReport reports[2];
  for (int reuse = 0; reuse < 2; ++reuse) {
    PrecomputedLargeDeformationOptions options;
    options.refactorAfter = 3; // a refactorization in any case
    if (reuse == 0)
      options.reuseTolerance = -1.0;
    SCOPED_TRACE("reuse " + std::to_string(reuse));
    SolveAsNewton(request, input, options, newton, reports[reuse]);
  }
  EXPECT_GE(reports[0].refactorizations, 1);
  EXPECT_EQ(reports[0].partialRefactorizations, 0);
  EXPECT_GE(reports[1].refactorizations, 1);
  EXPECT_EQ(reports[1].partialRefactorizations, reports[1].refactorizations);
}

TEST(PrecomputedLargeDeformation, AMoveBackTowardsRestStartsFromRest) {
  // After the 35 % press, a 5 % press is nearer the rest state than the pressed one: it starts
  // from rest with the rest factor, and equals the cold solve.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  auto system = Precomputed(request);
  ASSERT_TRUE(system);
  SolveResult result, cold;
  PrecomputedLargeDeformationReport report, coldReport;
  LargeDeformationState pressed, back;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, PlateMove(request, 0.35 * kLz), nullptr,
                                               result, report, &pressed)
                  .ok);
  WaitForRefactorization(*system); // the factor is now the pressed state's
  const SolveInput small = PlateMove(request, 0.05 * kLz);
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, small, &pressed, result, report, &back).ok);
  EXPECT_FALSE(report.warmStarted);
  EXPECT_TRUE(back.valid());
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, small, nullptr, cold, coldReport).ok);
  EXPECT_EQ(report.iterations, coldReport.iterations) << "the same start and factor";
  EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, cold.allDisplacement), kAgreement);
  // A move onwards from the pressed state still starts from it.
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, PlateMove(request, 0.36 * kLz), &pressed,
                                               result, report)
                  .ok);
  EXPECT_TRUE(report.warmStarted);
}

TEST(PrecomputedLargeDeformation, AnIterationLimitReturnsTheIterateAndSaysSo) {
  // The 35 % press: the iterate after k iterations is flagged, its residual above the tolerance
  // and shrinking with k, its distance to the equilibrium too; a limit the solve does not reach
  // gives the converged answer itself, and a limited solve leaves no state to start from.
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  const SolveInput input = PlateMove(request, 0.35 * kLz);
  // Every solve with the rest factor: the same iterates whatever the limit. The double-precision
  // factor: with it the distance to the equilibrium falls at every iteration on this block, which
  // the single-precision one's rounding does not promise below 1e-7.
  PrecomputedLargeDeformationOptions options;
  options.backgroundRefactorization = false;
  options.singlePrecisionFactor = false;
  auto system = Precomputed(request, options);
  ASSERT_TRUE(system);
  SolveResult exact;
  PrecomputedLargeDeformationReport full;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, nullptr, exact, full).ok);
  ASSERT_FALSE(full.stoppedAtLimit);
  ASSERT_GT(full.iterations, 2);
  double lastError = HUGE_VAL;
  for (int k = 1; k < full.iterations; ++k) {
    SolveResult result;
    PrecomputedLargeDeformationReport report;
    LargeDeformationState state;
    const Status s =
        SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report, &state, k);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_TRUE(report.stoppedAtLimit) << "k = " << k;
    EXPECT_FALSE(report.fellBack);
    EXPECT_EQ(report.iterations, k);
    EXPECT_GT(result.relativeResidual, 1e-9) << "k = " << k;
    EXPECT_FALSE(state.valid()) << "an unconverged iterate is no state to start from";
    const double error = RelativeMaxNodeDifference(result.allDisplacement, exact.allDisplacement);
    EXPECT_GT(error, 0.0);
    EXPECT_LT(error, lastError) << "k = " << k;
    lastError = error;
  }
  SolveResult result;
  PrecomputedLargeDeformationReport report;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report, nullptr,
                                               full.iterations + 5)
                  .ok);
  EXPECT_FALSE(report.stoppedAtLimit);
  EXPECT_LT(RelativeMaxNodeDifference(result.allDisplacement, exact.allDisplacement), 1e-14);
  const Status s =
      SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report, nullptr, -1);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("iteration limit"), std::string::npos) << s.message;
}

TEST(PrecomputedLargeDeformation, ABackendWithoutItsStepsLeavesThemToTheCpuAndSaysSo) {
  // The CPU backend has no large-deformation steps: the solve runs them on the CPU, gives the same
  // answer bit for bit, and says why the backend ran none. Without a backend nothing is said.
  PrecomputeRequest request = ShellRequest(4, 2);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request, 3.0);
  auto plain = Precomputed(request);
  request.options.backend = MakeCpuBackend();
  auto withBackend = Precomputed(request);
  ASSERT_TRUE(plain && withBackend);
  SolveResult a, b;
  PrecomputedLargeDeformationReport ra, rb;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*plain, input, nullptr, a, ra).ok);
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*withBackend, input, nullptr, b, rb).ok);
  EXPECT_EQ(ra.device, "CPU");
  EXPECT_EQ(ra.deviceNote, "");
  EXPECT_EQ(rb.device, "CPU");
  EXPECT_EQ(b.backend, "CPU");
  EXPECT_NE(rb.deviceNote.find("the CPU ran the forces"), std::string::npos) << rb.deviceNote;
  EXPECT_EQ(rb.deviceEvaluations, 0);
  EXPECT_EQ(rb.deviceSubstitutions, 0);
  EXPECT_EQ(RelativeMaxNodeDifference(a.keptDisplacement, b.keptDisplacement), 0.0);
  // With useBackend off the backend is not asked.
  PrecomputedLargeDeformationOptions off;
  off.useBackend = false;
  auto unused = Precomputed(request, off);
  ASSERT_TRUE(unused);
  PrecomputedLargeDeformationReport rc;
  ASSERT_TRUE(SolvePrecomputedLargeDeformation(*unused, input, nullptr, b, rc).ok);
  EXPECT_EQ(rc.deviceNote, "");
}

TEST(PrecomputedLargeDeformation, BadInputIsAnError) {
  const PrecomputeRequest request = PressedBlockRequest(kLx, kLy, kLz, kNu, kE);
  std::shared_ptr<LargeDeformationSystem> system;
  PrecomputeRequest quadratic = request;
  quadratic.options.elementOrder = ElementOrder::Quadratic;
  Status s = PrecomputeLargeDeformation(quadratic, {}, system);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("linear (4-node) elements"), std::string::npos) << s.message;
  EXPECT_FALSE(system);
  PrecomputedLargeDeformationOptions options;
  options.tolerance = 0.0;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.maxIterations = 0;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.settleTolerance = 0.0;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options.settleTolerance = std::nan("");
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.recheckTolerance = -1e-6;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options.recheckTolerance = std::nan("");
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.refactorCostIterations = -1.0;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.refactorCostIterationsOnDevice = std::nan("");
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.maxRestReleases = -1;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.aheadCorrections = -1;
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  options = {};
  options.reuseTolerance = std::nan("");
  EXPECT_FALSE(PrecomputeLargeDeformation(request, options, system).ok);
  PrecomputeRequest broken = request;
  broken.mesh.tets(0, 0) = -1;
  EXPECT_FALSE(PrecomputeLargeDeformation(broken, {}, system).ok);

  system = Precomputed(request);
  ASSERT_TRUE(system);
  SolveResult result;
  PrecomputedLargeDeformationReport report;
  SolveInput input = PlateMove(request, 1.0);
  input.movableDisplacement(0, 2) = std::nan("");
  EXPECT_FALSE(SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report).ok);
  input = PlateMove(request, 1.0);
  input.movableDisplacement.conservativeResize(3, 3);
  EXPECT_FALSE(SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report).ok);
  input = PlateMove(request, 1.0);
  input.nodalLoads = RowVectors3d::Zero(2, 3);
  EXPECT_FALSE(SolvePrecomputedLargeDeformation(*system, input, nullptr, result, report).ok);
}

} // namespace
