// SPDX-License-Identifier: BSD-3-Clause
// The large-deformation solve on small random meshes: a block of 1 or 2 cubes (six tetrahedra
// each) whose nodes move at random, random node classes (sliding ones with random normals),
// materials (some cells small-strain elastic), moves from 1e-7 to 10 cube sizes, lift-off and
// solver options. Promises checked: no crash or hang; an error has a message; a success is finite,
// converged to the requested tolerance and has no inverted cell; for tiny moves without lift-off
// (tiny also against the material's kappa / mu) it agrees with the linear model when that system is
// reasonably conditioned. The precomputed solve (PrecomputedLargeDeformation.h) runs on the same
// scene with random options, an iteration limit and a warm-started second move: the same promises,
// except that an iterate stopped at the limit is flagged instead of converged.
#include "FuzzBytes.h"
#include "FuzzPrecompute.h"

#include "CondensedFEM/LargeDeformation.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"
#include "Element/NeoHookeanTet.h"
#include "Support/BoxMeshGenerator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

using namespace faceplan;
using faceplan::fuzz::CheckedPrecompute;
using faceplan::fuzz::FuzzBytes;
using faceplan::fuzz::Violation;

namespace {

void CheckSolved(const PrecomputeRequest& request, const SolveResult& result, double volumeRatio) {
  if (!result.keptDisplacement.allFinite() || !result.allDisplacement.allFinite())
    Violation("the large-deformation solve succeeded with a non-finite displacement");
  if (result.keptDisplacement.rows() != Eigen::Index(request.sets.kept.size()))
    Violation("kept displacement has the wrong number of rows");
  if (!(volumeRatio > 0.0))
    Violation("the large-deformation solve succeeded with an inverted cell");
}

// The precomputed solve of `input`, after a first solve of half of it when `drag` (warm start).
void PrecomputedSolve(const PrecomputeRequest& request, const SolveInput& input,
                      const PrecomputedLargeDeformationOptions& options, int limit, bool drag) {
  std::shared_ptr<LargeDeformationSystem> system;
  const Status made = PrecomputeLargeDeformation(request, options, system);
  if (!made) {
    if (made.message.empty())
      Violation("a large-deformation precompute error without a message");
    return;
  }
  LargeDeformationState state;
  if (drag) {
    SolveInput half = input;
    half.movableDisplacement *= 0.5;
    half.gravity *= 0.5;
    SolveResult result;
    PrecomputedLargeDeformationReport report;
    if (!SolvePrecomputedLargeDeformation(*system, half, nullptr, result, report, &state))
      state = LargeDeformationState();
  }
  SolveResult result;
  PrecomputedLargeDeformationReport report;
  const Status solved =
      SolvePrecomputedLargeDeformation(*system, input, &state, result, report, nullptr, limit);
  if (!solved) {
    if (solved.message.empty())
      Violation("a precomputed large-deformation error without a message");
    return;
  }
  CheckSolved(request, result,
              report.fellBack ? report.newton.smallestVolumeRatio : report.smallestVolumeRatio);
  if (report.stoppedAtLimit) {
    if (limit <= 0 || report.iterations != limit)
      Violation("a precomputed solve stopped without reaching its iteration limit");
  } else if (!(result.relativeResidual <= options.tolerance)) {
    Violation("the precomputed large-deformation solve succeeded without converging");
  }
  if (report.fellBack && !options.fallBackToNewton)
    Violation("the precomputed solve fell back to Newton where it was told not to");
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzBytes in(data, size);
  PrecomputeRequest request;
  request.mesh = in.byte() % 4 == 0 ? MakeBoxTetMesh(2, 1, 1, 2.0, 1.0, 1.0)
                                    : MakeBoxTetMesh(1, 1, 1, 1.0, 1.0, 1.0);
  const int n = int(request.mesh.numPoints());
  // Jitter small enough to keep every cell positive (the Kuhn split's cells have volume 1/6).
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      request.mesh.points(i, c) += in.scaled(0.1);
  // Node classes: bit 0 constrained, bit 1 movable (when constrained), bit 2 kept, bit 3 sliding
  // (when constrained) with a random, possibly degenerate, normal.
  for (int i = 0; i < n; ++i) {
    const std::uint8_t classes = in.byte();
    if (classes & 1) {
      request.sets.constrained.push_back(i);
      if (classes & 8) {
        request.sets.sliding.push_back(i);
        Eigen::Vector3d normal;
        for (int c = 0; c < 3; ++c) // one read per statement: the same bytes under every compiler
          normal[c] = in.scaled(1.0);
        if (in.byte() % 8 != 0 && normal.norm() > 0.0)
          normal.normalize(); // one in eight left as it is: validation must refuse it
        request.sets.slidingNormal.push_back(normal);
      }
    }
    if ((classes & 3) == 3)
      request.sets.movable.push_back(i);
    if (classes & 4)
      request.sets.kept.push_back(i);
  }
  const double youngs = std::pow(10.0, in.range(-3, 9));
  const double poisson = in.flag() ? 0.49 * in.scaled(1.0) : 0.5 - std::pow(10.0, -in.range(1, 8));
  request.materials = Materials::Uniform(youngs, poisson, 1.0);
  if (in.byte() % 16 == 0)
    request.options.elementOrder = ElementOrder::Quadratic; // an error, with a message

  LargeDeformationOptions options;
  options.slidingLiftOff = in.flag();
  options.initialStep = std::max(1e-3, std::abs(in.scaled(1.0)));
  options.maxIterationsPerStep = in.range(1, 25);
  options.maxStepHalvings = in.range(0, 8);
  options.maxLoadSteps = in.range(1, 60);
  options.tolerance = std::pow(10.0, -in.range(4, 12));

  SolveInput input;
  const double moveExponent = -in.range(0, 7);
  const double moveScale = std::pow(10.0, moveExponent) * (in.flag() ? 10.0 : 1.0);
  const bool special = in.byte() % 16 == 0; // NaN, infinite, huge or denormal values
  input.movableDisplacement.resize(Eigen::Index(request.sets.movable.size()), 3);
  for (Eigen::Index i = 0; i < input.movableDisplacement.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      input.movableDisplacement(i, c) = special ? in.number(moveScale) : in.scaled(moveScale);
  if (in.flag())
    for (int c = 0; c < 3; ++c)
      input.gravity[c] = in.scaled(10.0);
  input.recoverInterior = in.flag();

  const bool precomputed = in.flag();
  PrecomputedLargeDeformationOptions quasiNewton;
  quasiNewton.tolerance = options.tolerance;
  quasiNewton.slidingLiftOff = options.slidingLiftOff;
  quasiNewton.historySize = in.range(0, 10);
  quasiNewton.maxIterations = in.range(1, 60);
  quasiNewton.refactorAfter = in.range(0, 20);
  quasiNewton.maxRefactorizations = in.range(0, 3);
  quasiNewton.maxSubstepHalvings = in.range(0, 4);
  quasiNewton.backgroundRefactorization = in.flag();
  quasiNewton.fallBackToNewton = in.flag();
  quasiNewton.newton = options;
  const int limit = in.flag() ? in.range(1, 8) : 0;
  const bool drag = in.flag();
  quasiNewton.singlePrecisionFactor = in.flag();
  quasiNewton.factorAhead = in.flag();
  quasiNewton.factorAheadOrder = in.flag() ? 2 : 1;
  quasiNewton.maxCoupledReleases = in.range(0, 8);
  if (in.flag()) { // some cells small-strain elastic (as LipSeal's bridges), for both solvers
    request.materials.smallStrain.resize(static_cast<size_t>(request.mesh.numTets()));
    for (auto& flag : request.materials.smallStrain)
      flag = in.flag() ? 1 : 0;
  }
  // Read last, so that the corpus's earlier bytes keep their meaning.
  quasiNewton.adaptiveRefactorization = in.flag();
  quasiNewton.coupleRestReleases = !in.flag();            // past the end: the default (on)
  quasiNewton.maxRestReleases = 1024 - in.range(0, 1024); // past the end: the default
  quasiNewton.settleTolerance = std::pow(10.0, -in.range(1, 9));
  quasiNewton.predictContactAhead = in.flag();
  quasiNewton.recheckTolerance = in.flag() ? 0.0 : 1e-6; // past the end: the default
  quasiNewton.aheadCorrections = 2 - in.range(0, 2);     // past the end: the default
  if (precomputed)
    PrecomputedSolve(request, input, quasiNewton, limit, drag);

  SolveResult result;
  LargeDeformationReport report;
  const Status solved = SolveLargeDeformation(request, input, options, result, report);
  if (!solved) {
    if (solved.message.empty())
      Violation("a large-deformation error without a message");
    return 0;
  }
  CheckSolved(request, result, report.smallestVolumeRatio);
  if (!(result.relativeResidual <= options.tolerance))
    Violation("the large-deformation solve succeeded without converging");

  // Tiny moves, no loads, two-way contact: the linear model's answer to first order.
  if (special || options.slidingLiftOff || moveScale > 1e-5 || input.gravity.squaredNorm() > 0.0)
    return 0;
  std::shared_ptr<const CondensedSystem> system;
  if (!CheckedPrecompute(request, system))
    return 0;
  SolveResult linear;
  if (!Solve(*system, input, linear))
    return 0;
  const double scale =
      linear.keptDisplacement.size() ? linear.keptDisplacement.cwiseAbs().maxCoeff() : 0.0;
  const double difference =
      result.keptDisplacement.size()
          ? (result.keptDisplacement - linear.keptDisplacement).cwiseAbs().maxCoeff()
          : 0.0;
  // The models differ by about the strain times the stiffest modulus ratio (the volumetric term
  // is quadratic in the strain with kappa / mu times the shear term's weight): near-incompressible
  // tissue leaves the linear range at far smaller strains. The cells are about 1 long, so the
  // largest displacement bounds the strain.
  const NeoHookeanParameters moduli = NeoHookeanFromLinear(youngs, poisson);
  const double nonlinearity = scale * std::max(1.0, moduli.kappa / moduli.mu);
  const double condition = Describe(*system).conditionEstimate;
  if (condition < 1e4 && nonlinearity < 1e-5 &&
      difference > 1e-3 * scale + 1e-3 * options.tolerance * moveScale + 1e-300) {
    std::fprintf(stderr, "condition %.3g, move %.3g, nonlinearity %.3g, difference %.3g of %.3g\n",
                 condition, moveScale, nonlinearity, difference, scale);
    Violation("a tiny large-deformation move disagrees with the linear model");
  }
  return 0;
}
