// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The large-deformation model (LargeDeformation.h: the same compressible neo-Hookean equilibrium,
// node frames, sliding and lift-off contact, tolerance) split into a precompute and a solve, so
// that an edit costs no numeric factorization.
//
// Precompute (on a worker thread): the node frames, the assembly pattern, the METIS ordering and
// the symbolic analysis of the whole-mesh tangent without the couplings of the nodes that every
// solve pins (FactorPattern in the .cpp), and the numeric factor of the rest-pose tangent
// (prescribed DOFs keep their diagonal; their rows and columns are zero).
//
// Solve: L-BFGS on the free DOFs whose initial inverse Hessian is that factor (Liu, Bouaziz &
// Kavan, ACM TOG 2017), with a predictor that moves the prescribed DOFs and lets the free ones
// follow the factored tangent. The two-loop recursion is written here: LBFGS++ scales a multiple of
// the identity as its initial Hessian and has no hook for a factor, nor for a step that must keep
// every cell's det F > 0 (the line search here rejects such steps). Every accepted step keeps det F
// > 0. After a converged solve the tangent is factored again on a background thread (with that
// state's contact): at the converged state, or, after a drag step (a warm solve whose move changed
// little), one step ahead, where the same change again would lead: at 2 u - u_before, or after two
// equal changes at the parabola through the last three states, 3 (u - u_before) + u_2before, with
// the contact that Newton's rule gives there (predictContactAhead); that state is then corrected
// by Newton steps, the tangent factored again where each leads (aheadCorrections), unless the next
// edit comes first. A solve whose targets are
// nearer the factor's state than its start starts there, with that contact, so its predictor is
// Newton's own step at the state the factor was made at and the drag's next step converges in a
// couple of iterations. Within a solve, the current tangent is factored (modified Newton with a
// refresh, and the L-BFGS history restarted) when the last iterations' rate predicts more
// iterations with the present factor than a factorization costs, counted in iterations
// (`adaptiveRefactorization`), and in any case after `refactorAfter` iterations of a sub-step.
// The factor is computed in single precision (SinglePrecisionFactor::factorize; where single
// precision breaks down, as a double factor rounded to single): the factorization takes about half
// the time, the substitutions read half the bytes, and the initial Hessian need not be exact, as
// the residual that decides convergence is evaluated in double precision.
//
// Lift-off (unilateral contact): the factor is made with the contact of its state pinned. A DOF
// free now but pinned in the factor is coupled back in through its Schur complement: with the rest
// factor any number of them (the coupling of every lift-off DOF is made once, on the worker thread
// after the precompute: a move from rest releases the lips' nodes layer after layer, tens of DOFs
// at a time), with another factor a few (a drag step releasing a node or two); beyond that it gets
// the factor's diagonal (its row decoupled). A DOF pinned now but free in the factor is projected
// out (the initial inverse Hessian is P F^-1 P, P zeroing the pinned DOFs), which stays symmetric
// positive definite on the free DOFs, so L-BFGS minimises the energy over exactly the free DOFs.
// The active set is updated with Newton's rule (UpdateContact) on states converged to
// `settleTolerance` (and checked again at `recheckTolerance`), and before a refactorization within
// a solve (its releases only, so that the new factor has the DOFs free that the tighter state
// releases), and the final state is converged to the tolerance with no change left: the constrained
// equilibrium Newton finds (the tests compare them).
//
// Warm start: a solve may start from the last converged state (only the prescribed values or
// loads changed); the prescribed values and loads then go from that state's to the new ones (and
// where they are that state's own, it is returned as it is). A move back towards rest starts from
// rest with the rest factor instead. A sub-step that inverts a
// cell or does not converge is halved. When the solve does not converge within its bounds it falls
// back to Newton (SolveLargeDeformation) and says so in the report; it never returns an unconverged
// answer unless the caller set an iteration limit, and then it says so.
//
// Why L-BFGS with the factor (the figures: BENCHMARKS.md, "large deformations"): an iteration costs
// one force evaluation and one substitution, no tangent and no factorization, against Newton's
// numeric factorization per iteration. From a converged state with the refreshed factor a small
// drag step takes a few iterations, because the predictor with that factor is Newton's own first
// step, and one or two when the factor was made ahead. From rest the rest tangent is a poor model
// of strains near 100 % and each lift-off change restarts the history, so a whole move takes tens
// of iterations and a refactorization or two. A Newton-Krylov variant (the tangent assembled, CG
// preconditioned by the same factor) would pay the tangent's element matrices and assembly every
// outer iteration on top of the same substitutions.
#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/LargeDeformation.h"

#include <atomic>
#include <memory>
#include <string>
#include <vector>

namespace faceplan {

struct PrecomputedLargeDeformationOptions {
  double tolerance = 1e-9; // as LargeDeformationOptions::tolerance
  bool slidingLiftOff = false;
  // With lift-off: the relative residual at which the contact is updated before the final solve
  // to `tolerance`. Loose, because each update restarts the L-BFGS history and a contact found at
  // a loose residual is corrected by the final check (Newton, which pays a factorization per
  // iteration, settles at kSettleTolerance).
  double settleTolerance = 1e-3;
  // With lift-off: once the contact holds at settleTolerance, it is checked again at this relative
  // residual on the way to `tolerance` (0: not). A node whose normal force is near zero may change
  // side only as the residual falls; found here, its change costs the iterations from this
  // residual's state instead of from a converged one (the six osteotomy full moves: 131 iterations
  // against 141).
  double recheckTolerance = 1e-6;
  int historySize = 8; // L-BFGS pairs kept
  // Quasi-Newton iterations over the whole solve; past it the solve falls back to Newton.
  int maxIterations = 400;
  // A sub-step that has run this many iterations without converging factors the tangent at its
  // current state (0: never).
  int refactorAfter = 40;
  // Also factor the tangent at the current state when the rate of the last iterations predicts
  // that finishing with the present factor takes longer than a factorization, which costs as much
  // as refactorCostIterations iterations with the CPU's substitutions (the single-precision
  // factorization, its tangent and assembly take 9-12 iterations' time on the 2-core machine of
  // BENCHMARKS.md; the rate's prediction errs on the slow side, as contact changes slow the
  // iterations that follow, hence the lower end) and refactorCostIterationsOnDevice with a
  // backend's (whose iterations are 10-20 times quicker while the factorization stays on the CPU).
  // A count rather than a timing: the same input gives the same result on every run. The
  // prediction is to `tolerance`; while the contact settles at settleTolerance, to that in a
  // warm-started solve and to `tolerance` in one from rest.
  bool adaptiveRefactorization = true;
  double refactorCostIterations = 10.0;
  double refactorCostIterationsOnDevice = 300.0;
  int maxRefactorizations = 4; // per solve
  int maxSubstepHalvings = 8;
  int maxContactUpdates = 100;
  // After a converged solve, factor the tangent at its state on a background thread.
  bool backgroundRefactorization = true;
  // After a drag step (a warm solve of the same loads whose prescribed change is no larger than
  // the move), factor where the same change again would lead (extrapolated from the drag's last
  // two or three states) rather than at u.
  bool factorAhead = true;
  // How far ahead is extrapolated: 1, the line through the last two states; 2, after two equal
  // changes (a steady drag), the parabola through the last three.
  int factorAheadOrder = 2;
  // With lift-off, the factor made ahead takes the contact that Newton's rule gives at the state
  // ahead (with the targets and loads extrapolated there), and a solve that starts from that
  // factor's state starts with its contact: a drag that lifts the tissue off node after node then
  // finds each node already free in its factor, where it would otherwise change the contact, couple
  // the node back in and iterate again. The contact updates still decide the final contact.
  bool predictContactAhead = true;
  // Once the factor ahead is made (and taken by the solves), if no solve asks for another
  // refactorization within 0.2 s (a pause in the drag), the state ahead is corrected by up to this
  // many Newton steps (with the targets and loads extrapolated there), each with the last factor,
  // the tangent factored again where each leads. The next drag step's predictor, a Newton step
  // from the factor's state, then starts nearer its equilibrium: on the osteotomy demos and a
  // rigid segment one correction lets the predictor alone converge; on a shell's bending field the
  // steady steps take 6-9 iterations with none, 2-6 with one, 0-3 with two (BENCHMARKS.md). Each
  // is a factorization on the worker thread, in the surgeon's pause; the next edit ends them.
  int aheadCorrections = 2;
  // Lift-off DOFs freed since the factor was made are coupled back into the initial Hessian
  // through their Schur complement: any number of them with the rest factor (whose coupling of
  // every lift-off DOF is made once, after the precompute), at most this many with another factor
  // (their columns substituted at once, once per contact change). Each iteration reads their
  // coupling twice.
  int maxCoupledReleases = 8;
  // Make the rest factor's coupling of every lift-off DOF (with singlePrecisionFactor; false: a
  // move from rest couples at most maxCoupledReleases DOFs, as with any factor), where there are at
  // most maxRestReleases of them (its making holds two n x |L| matrices and the worker thread for
  // |L| substitutions' worth of work; the face's scenes have 79-182) and those matrices stay
  // under 512 MB.
  bool coupleRestReleases = true;
  int maxRestReleases = 1024;
  // Later factorizations reuse the rest factor's supernodes whose tangent entries (and their
  // descendants') changed by at most reuseTolerance times sqrt(|k_ii k_jj|) of the rest tangent's
  // diagonal (MultifrontalReference; with singlePrecisionFactor). A move strains part of the face:
  // on the main demo's cut a tangent there changes beyond 1e-2 in the columns of two fifths of the
  // factorization's flops. Such a factor is the exact factor of the tangent with the rest values
  // in the reused columns; the initial Hessian only steers the iterations, whose residual decides
  // convergence, so the result is the same equilibrium. Negative: every factorization is whole.
  double reuseTolerance = 1e-2;
  // The initial inverse Hessian from a factor in single precision (about half the factorization's
  // time and half the bytes a substitution reads); the residual, and so the result, stay double
  // precision. False: a double-precision factor.
  bool singlePrecisionFactor = true;
  // When the solve does not converge: Newton (true) or an error (false, for tests).
  bool fallBackToNewton = true;
  // With a request whose backend has the large-deformation steps (the CUDA backend): the cells'
  // forces, the factor's substitutions and the tangent's products run there, the rest of the
  // iteration (L-BFGS's vectors, the line search, the contact) on the CPU. Needs
  // singlePrecisionFactor. Where the backend cannot (no device, a factor that does not fit), the
  // CPU does that step and the report says so.
  bool useBackend = true;
  LargeDeformationOptions newton; // the fallback's (slidingLiftOff and tolerance are set from here)
};

// The precompute's data (opaque). Solves may run while its background refactorization does; two
// solves on one system must not run at once.
class LargeDeformationSystem;

// Precomputes for `request` (linear cells only; validated as SolveLargeDeformation does).
Status PrecomputeLargeDeformation(const PrecomputeRequest& request,
                                  const PrecomputedLargeDeformationOptions& options,
                                  std::shared_ptr<LargeDeformationSystem>& system);

// A converged state of one system, from which a later solve may start.
struct LargeDeformationState {
  const LargeDeformationSystem* system = nullptr;
  Eigen::VectorXd u;            // every DOF, in the nodes' frames
  std::vector<char> prescribed; // per DOF (lift-off's contact included)
  Eigen::VectorXd target, load; // what it is the equilibrium for
  Eigen::VectorXd force;        // the internal force at u
  // When this state ended a drag step: the state that step started from and its targets (the
  // drag's previous point, for a second-order extrapolation of the next); else empty.
  Eigen::VectorXd before, targetBefore;
  bool valid() const { return system != nullptr; }
};

struct PrecomputedLargeDeformationReport {
  bool warmStarted = false;
  int iterations = 0;   // quasi-Newton iterations (evaluations of the forces, line search aside)
  int evaluations = 0;  // force evaluations, line search included
  int factorSolves = 0; // substitutions with the factor
  int substeps = 0;     // accepted sub-steps of the prescribed change
  int rejectedSubsteps = 0;
  int refactorizations = 0;        // numeric factorizations in this solve (slow convergence)
  int partialRefactorizations = 0; // of them, those that reused the rest factor in part
  int contactUpdates = 0;
  int liftedNodes = 0;
  double smallestVolumeRatio = 1.0;
  double largestGreenStrain = 0.0;
  long long largestStrainCell = -1;
  // Fallback: why the precomputed solve did not converge, and Newton's report.
  bool fellBack = false;
  std::string fallbackReason;
  // The solve stopped at the caller's iteration limit before it converged: the result is that
  // iterate, not the equilibrium (for studies of error against iterations).
  bool stoppedAtLimit = false;
  LargeDeformationReport newton;
  // Where the forces and substitutions ran: the backend's name, or "CPU"; and, when a backend was
  // asked for and did not take a step, why.
  std::string device = "CPU";
  std::string deviceNote;
  int deviceEvaluations = 0, deviceSubstitutions = 0;
  // Wall time of the solve's parts outside its iterations: the values and the yardstick before
  // them, the measures and the result's rows after.
  double setupMs = 0.0, finishMs = 0.0;
  // Per iteration: time since the solve started (ms) and the relative residual.
  std::vector<std::pair<double, double>> convergence;
};

// Solves for `input` (as SolveLargeDeformation) with the precomputed system, from `warm` when it
// is a converged state of this system and the new targets and loads are nearer it than the rest
// state (then with the latest background factor), else from the rest state with the rest factor.
// `converged` (optional) receives the converged state (invalid after a fallback to Newton or a stop
// at the limit). `iterationLimit` > 0 stops after that many quasi-Newton iterations and returns the
// iterate unconverged, flagged in report.stoppedAtLimit (no fallback); an error if the whole
// prescribed move was not yet applied then.
Status SolvePrecomputedLargeDeformation(LargeDeformationSystem& system, const SolveInput& input,
                                        const LargeDeformationState* warm, SolveResult& result,
                                        PrecomputedLargeDeformationReport& report,
                                        LargeDeformationState* converged = nullptr,
                                        int iterationLimit = 0);

// Blocks until no background refactorization is running or queued (benchmarks and tests).
void WaitForRefactorization(LargeDeformationSystem& system);
// Ends the background refactorization for good (before the process exits: a factorization must
// not run while the libraries it uses are torn down). Solves go on with the factor they have.
void StopRefactorization(LargeDeformationSystem& system);
// The precompute's stage times (Reordering, ElementStiffness, Assembly, Factorization, Total).
StageTimings PrecomputeTimings(const LargeDeformationSystem& system);
// The backend's copy of the latest factor described (FactorOnDevice::describe), or why there is
// none.
std::string DescribeFactorOnDevice(const LargeDeformationSystem& system);
// Refactorizations completed in the background so far.
int BackgroundRefactorizations(const LargeDeformationSystem& system);
// States ahead of a drag whose tangent could not be factored (a cell inverted there, or the
// tangent not positive definite), so that the converged state's was factored instead.
int FactorsAheadRefused(const LargeDeformationSystem& system);
// Newton steps that corrected a state ahead of a drag, each factored again (aheadCorrections).
int FactorsAheadCorrected(const LargeDeformationSystem& system);

} // namespace faceplan
