// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Large-deformation solve: the same mesh, node sets and prescribed values as the condensed linear
// model, with a compressible neo-Hookean material (Element/NeoHookeanTet.h) solved by Newton's
// method with load stepping. It is for the moves a linear model cannot take (Solve warns when its
// largest strain exceeds the small-strain limit): strains of tens of percent and large rotations.
// Every update runs the whole iteration (a numeric factorization per iteration): it is the
// reference and the fallback of PrecomputedLargeDeformation.h, the same model split into a
// precompute and a solve for dragging.
//
// Sliding nodes keep the linear model's constraint: the displacement along the node's undeformed
// normal is prescribed and the tangential components are free; with slidingLiftOff the normal
// one only bounds the tissue from the bone's side (unilateral contact, an active set that is
// settled at every load step). Loads (gravity, nodal loads) are
// dead loads that grow with the prescribed values.
#include "CondensedFEM/CondensedFEM.h"

#include <functional>
#include <utility>
#include <vector>

namespace faceplan {

struct LargeDeformationOptions {
  // Converged when the free DOFs' residual force is at most this fraction of the largest of: the
  // internal force (over all DOFs), the loads, and the force the linear model needs for the whole
  // prescribed move (the yardstick when the internal force vanishes, as in a rigid motion); for
  // strains below 1e-5 the force of a 1e-5 strain stands in (round-off floor).
  double tolerance = 1e-9;
  int maxIterationsPerStep = 25;
  // The load steps start with this fraction of the prescribed values and loads; a step whose
  // Newton iteration fails (a cell would invert, or it does not converge) is halved, at most
  // maxStepHalvings times in a row; a step that converges quickly doubles the next one.
  double initialStep = 1.0;
  int maxStepHalvings = 12;
  int maxLoadSteps = 200;
  // Newton iterations over the whole solve (accepted and rejected steps): bounds its time.
  int maxTotalIterations = 400;
  // Unilateral contact: a sliding node may lift off its bone (move away along the normal) where
  // the contact would otherwise pull the tissue onto it, and comes back where it would go into
  // the bone. Off: the normal displacement is prescribed both ways, as in the linear model.
  bool slidingLiftOff = false;
  int maxContactUpdatesPerStep = 30;
  int maxContactUpdates = 100; // over the whole solve
  // Called on the calling thread after each accepted load step with the fraction of the move
  // reached (for a progress bar).
  std::function<void(double fraction)> progress;
};

struct LargeDeformationReport {
  int loadSteps = 0;        // accepted load steps
  int rejectedSteps = 0;    // steps halved because a cell would invert or Newton did not converge
  int newtonIterations = 0; // over all accepted and rejected steps
  double smallestVolumeRatio = 1.0; // min over cells of det F
  double largestGreenStrain = 0.0;  // max over cells of |principal Green-Lagrange strain|
  long long largestStrainCell = -1;
  int contactUpdates = 0; // lift-off: solves repeated because the contact changed
  int liftedNodes = 0;    // lift-off: sliding nodes off their bone in the result
  // Per Newton iterate: time since the solve started (ms) and its relative residual.
  std::vector<std::pair<double, double>> convergence;
};

// Linear cells only (request.options.elementOrder must be Linear). Fills result like Solve (kept
// rows, every node when input.recoverInterior, the relative residual, timings) with largestStrain
// the largest |principal Green-Lagrange strain| and no small-strain warning; segment transforms
// are not needed (the displacements are the boundary values).
Status SolveLargeDeformation(const PrecomputeRequest& request, const SolveInput& input,
                             const LargeDeformationOptions& options, SolveResult& result,
                             LargeDeformationReport& report);

} // namespace faceplan
