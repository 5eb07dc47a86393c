// Newton's method on the total potential energy, in each node's frame (a sliding node's frame is
// its normal and two tangents, every other node's the identity), so that each prescribed value is
// one DOF. Prescribed DOFs get a unit row and column in the tangent, which keeps one sparsity
// pattern and one symbolic factorization for every iteration.
#include "CondensedFEM/LargeDeformation.h"

#include "Common/ExceptionBoundary.h"
#include "Common/ParallelFor.h"
#include "CondensedFEM/NodeLayout.h"
#include "Element/NeoHookeanTet.h"
#include "Element/StiffnessAssembly.h"
#include "Mesh/InputValidation.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/FillReducingOrdering.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numeric>
#include <sstream>

namespace faceplan {

namespace {

struct Problem {
  const TetMesh* mesh = nullptr;
  Eigen::Index n = 0;
  std::vector<int> frameOf;            // node -> index into frames, -1 for the identity
  std::vector<Eigen::Matrix3d> frames; // columns: normal, two tangents
  std::vector<char> prescribed;        // per DOF, in the node's frame
  Eigen::VectorXd target;              // prescribed DOFs' full values, 0 elsewhere
  Eigen::VectorXd externalLoad;        // full dead load, in the nodes' frames
  std::vector<TetReference> cells;
  std::vector<NeoHookeanParameters> materials;
  AssemblyPattern pattern;
  std::vector<int> prescribedEntries; // nonzeros of the upper triangle in a prescribed row/column
  std::vector<int> prescribedDiagonal;
  // Sliding nodes' normal DOFs when the tissue may lift off the bone (unilateral contact), and
  // whether each is in contact (prescribed) now.
  std::vector<int> liftOffDofs;
  // The force the linear model needs for the whole prescribed move (|K_0 u_prescribed|): the
  // residual's yardstick where the internal forces vanish, as in a rigid motion.
  double linearForce = 0.0;
  // |K_0 X| for the node positions X: the force of a unit strain. A small fraction of it is the
  // yardstick's floor, where the stress's cancellation (F against F^-T near the identity) leaves
  // round-off in the residual that a relative tolerance cannot get below.
  double unitStrainForce = 0.0;

  Eigen::Vector3d toGlobal(int node, const Eigen::Vector3d& local) const {
    return frameOf[node] < 0 ? local : Eigen::Vector3d(frames[frameOf[node]] * local);
  }
  Eigen::Vector3d toLocal(int node, const Eigen::Vector3d& global) const {
    return frameOf[node] < 0 ? global : Eigen::Vector3d(frames[frameOf[node]].transpose() * global);
  }
};

// Internal energy, internal force and (when packed is given) the packed tangents at u (nodes'
// frames). False when a cell would be inverted or degenerate.
struct Evaluation {
  double energy = 0.0;
  Eigen::VectorXd force;
};

bool Evaluate(const Problem& pb, const Eigen::VectorXd& u, Evaluation& out,
              std::vector<double>* packed) {
  const TetMesh& mesh = *pb.mesh;
  const Eigen::Index m = mesh.numTets();
  std::vector<double> energy(static_cast<size_t>(m));
  std::vector<ElementVector> force(static_cast<size_t>(m));
  if (packed)
    packed->resize(static_cast<size_t>(m) * kPackedElementSize);
  std::vector<char> valid(static_cast<size_t>(m), 1);
  ParallelFor(m, 4000, [&](std::int64_t begin, std::int64_t end) {
    CornerDisplacements corner;
    ElementMatrix tangent;
    for (std::int64_t e = begin; e < end; ++e) {
      int node[4];
      for (int a = 0; a < 4; ++a) {
        node[a] = mesh.tets(e, a);
        corner.row(a) = pb.toGlobal(node[a], u.segment<3>(3 * node[a])).transpose();
      }
      ElementVector f;
      if (!NeoHookeanTetState(pb.cells[e], pb.materials[e], corner, energy[e], f,
                              packed ? &tangent : nullptr)) {
        valid[e] = 0;
        continue;
      }
      for (int a = 0; a < 4; ++a) {
        const int fa = pb.frameOf[node[a]];
        if (fa < 0)
          continue;
        const Eigen::Matrix3d& Q = pb.frames[fa];
        f.segment<3>(3 * a) = Q.transpose() * f.segment<3>(3 * a);
        if (packed) {
          tangent.middleRows<3>(3 * a) = (Q.transpose() * tangent.middleRows<3>(3 * a)).eval();
          tangent.middleCols<3>(3 * a) = (tangent.middleCols<3>(3 * a) * Q).eval();
        }
      }
      force[e] = f;
      if (packed) {
        double* o = packed->data() + static_cast<size_t>(e) * kPackedElementSize;
        for (int p = 0; p < 12; ++p)
          for (int q = p; q < 12; ++q)
            *o++ = tangent(p, q);
      }
    }
  });
  if (std::find(valid.begin(), valid.end(), 0) != valid.end())
    return false;
  out.energy = 0.0;
  out.force = Eigen::VectorXd::Zero(3 * pb.n);
  for (Eigen::Index e = 0; e < m; ++e) {
    out.energy += energy[e];
    for (int a = 0; a < 4; ++a)
      out.force.segment<3>(3 * mesh.tets(e, a)) += force[e].segment<3>(3 * a);
  }
  return std::isfinite(out.energy) && out.force.allFinite();
}

void ZeroPrescribed(const Problem& pb, Eigen::VectorXd& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (pb.prescribed[i])
      v[i] = 0.0;
}

// The tangent with unit rows and columns for the prescribed DOFs.
void PinPrescribed(Problem& pb) {
  double* values = pb.pattern.upper.valuePtr();
  for (int k : pb.prescribedEntries)
    values[k] = 0.0;
  for (int k : pb.prescribedDiagonal)
    values[k] = 1.0;
}

// The tangent's nonzeros that PinPrescribed overwrites, for the current prescribed DOFs.
void FindPinnedEntries(Problem& pb) {
  pb.prescribedEntries.clear();
  pb.prescribedDiagonal.clear();
  const SparseMatrix& upper = pb.pattern.upper;
  for (int col = 0; col < upper.outerSize(); ++col)
    for (int k = upper.outerIndexPtr()[col]; k < upper.outerIndexPtr()[col + 1]; ++k) {
      const int row = upper.innerIndexPtr()[k];
      if (row == col && pb.prescribed[col])
        pb.prescribedDiagonal.push_back(k);
      else if (pb.prescribed[row] || pb.prescribed[col])
        pb.prescribedEntries.push_back(k);
    }
}

// For lift-off the normal must point from the bone into the tissue: the side where the node's
// cells lie (the sum of their centroids' offsets from the node).
Eigen::Vector3d IntoTissue(const TetMesh& mesh, const std::vector<std::vector<int>>& cellsOfNode,
                           int node, const Eigen::Vector3d& normal) {
  Eigen::Vector3d towardCells = Eigen::Vector3d::Zero();
  for (int e : cellsOfNode[node]) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a)
      centroid += mesh.points.row(mesh.tets(e, a)).transpose();
    towardCells += 0.25 * centroid - mesh.points.row(node).transpose();
  }
  return normal.dot(towardCells) < 0.0 ? Eigen::Vector3d(-normal) : normal;
}

Status Setup(const PrecomputeRequest& request, const SolveInput& input, bool liftOff, Problem& pb) {
  const TetMesh& mesh = request.mesh;
  const NodeSets& sets = request.sets;
  pb.mesh = &mesh;
  pb.n = mesh.numPoints();
  const Eigen::Index n = pb.n;
  pb.frameOf.assign(n, -1);
  std::vector<std::vector<int>> cellsOfNode(liftOff ? n : 0);
  for (Eigen::Index e = 0; liftOff && e < mesh.numTets(); ++e)
    for (int a = 0; a < 4; ++a)
      cellsOfNode[mesh.tets(e, a)].push_back(static_cast<int>(e));
  for (size_t s = 0; s < sets.sliding.size(); ++s) {
    const int node = sets.sliding[s];
    pb.frameOf[node] = static_cast<int>(pb.frames.size());
    pb.frames.push_back(NormalFrame(liftOff
                                        ? IntoTissue(mesh, cellsOfNode, node, sets.slidingNormal[s])
                                        : sets.slidingNormal[s]));
    if (liftOff)
      pb.liftOffDofs.push_back(3 * node);
  }
  // Prescribed DOFs: every DOF of a constrained node (only the normal one when sliding) and of a
  // node no cell uses.
  pb.prescribed.assign(3 * n, 0);
  pb.target = Eigen::VectorXd::Zero(3 * n);
  std::vector<char> used(n, 0);
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int a = 0; a < 4; ++a)
      used[mesh.tets(e, a)] = 1;
  for (Eigen::Index i = 0; i < n; ++i)
    if (!used[i])
      pb.prescribed[3 * i] = pb.prescribed[3 * i + 1] = pb.prescribed[3 * i + 2] = 1;
  for (int node : sets.constrained) {
    const int dofs = pb.frameOf[node] >= 0 ? 1 : 3;
    for (int c = 0; c < dofs; ++c)
      pb.prescribed[3 * node + c] = 1;
  }
  for (size_t k = 0; k < sets.movable.size(); ++k) {
    const int node = sets.movable[k];
    const Eigen::Vector3d local =
        pb.toLocal(node, input.movableDisplacement.row(static_cast<Eigen::Index>(k)).transpose());
    const int dofs = pb.frameOf[node] >= 0 ? 1 : 3;
    pb.target.segment(3 * node, dofs) = local.head(dofs);
  }

  pb.cells.resize(static_cast<size_t>(mesh.numTets()));
  pb.materials.resize(pb.cells.size());
  Eigen::VectorXd load = Eigen::VectorXd::Zero(3 * n);
  TetCorners corners;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int a = 0; a < 4; ++a)
      corners.row(a) = mesh.points.row(mesh.tets(e, a));
    pb.cells[e] = MakeTetReference(corners);
    pb.materials[e] = NeoHookeanFromLinear(request.materials.E(e), request.materials.nu(e));
    if (input.gravity.squaredNorm() > 0.0) {
      const double quarter = request.materials.rho(e) * pb.cells[e].volume / 4.0;
      for (int a = 0; a < 4; ++a)
        load.segment<3>(3 * mesh.tets(e, a)) += quarter * input.gravity;
    }
  }
  if (input.nodalLoads.size() > 0) {
    if (input.nodalLoads.rows() != n || !input.nodalLoads.allFinite())
      return Status::Error("nodal loads must be finite, one row per mesh point");
    for (Eigen::Index i = 0; i < n; ++i)
      load.segment<3>(3 * i) += input.nodalLoads.row(i).transpose();
  }
  pb.externalLoad.resize(3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    pb.externalLoad.segment<3>(3 * i) = pb.toLocal(static_cast<int>(i), load.segment<3>(3 * i));

  std::vector<int> identity(n);
  std::iota(identity.begin(), identity.end(), 0);
  const Status built = BuildAssemblyPattern(mesh, identity, static_cast<int>(n), pb.pattern);
  if (!built)
    return built;
  FindPinnedEntries(pb);
  return Status::Ok();
}

// Strains below this are measured against the unit-strain force instead (see unitStrainForce).
constexpr double kRoundOffStrain = 1e-5;

struct StepState {
  Eigen::VectorXd u;   // nodes' frames
  double fraction = 0; // of the prescribed values and loads
};

// Total potential energy and the free DOFs' residual at u for the load fraction s.
struct Balance {
  double potential = 0.0;
  Eigen::VectorXd residual; // zero on prescribed DOFs
  double scale = 0.0;       // what the residual is measured against
};
Balance BalanceOf(const Problem& pb, const Evaluation& ev, const Eigen::VectorXd& u, double s) {
  Balance b;
  b.potential = ev.energy - s * pb.externalLoad.dot(u);
  b.residual = ev.force - s * pb.externalLoad;
  ZeroPrescribed(pb, b.residual);
  b.scale = std::max({ev.force.norm(), s * pb.externalLoad.norm(), pb.linearForce,
                      kRoundOffStrain * pb.unitStrainForce});
  return b;
}

class NewtonSolver {
public:
  NewtonSolver(Problem& pb, const LargeDeformationOptions& options, CholmodFactor& factor,
               LargeDeformationReport& report, StageTimings& timings)
      : pb_(pb), options_(options), factor_(factor), report_(report), timings_(timings) {}

  // From a converged state at `from` to the load fraction `to`. True when converged there.
  bool step(const StepState& from, double to, double tolerance, StepState& reached, Status& error) {
    Evaluation ev;
    Eigen::VectorXd u = from.u;
    if (!evaluate(u, ev, true))
      return false;
    // Predictor: the prescribed DOFs move to their new values and the free ones follow the
    // tangent's response, K_ff du_f = -(r_f + K_fp du_p - ds f_ext,f).
    const double ds = to - from.fraction;
    Eigen::VectorXd prescribedMove = Eigen::VectorXd::Zero(u.size());
    for (Eigen::Index i = 0; i < u.size(); ++i)
      if (pb_.prescribed[i])
        prescribedMove[i] = to * pb_.target[i] - u[i];
    Eigen::VectorXd rhs = pb_.pattern.upper.selfadjointView<Eigen::Upper>() * prescribedMove;
    rhs += ev.force - to * pb_.externalLoad;
    rhs = -rhs;
    ZeroPrescribed(pb_, rhs);
    Eigen::VectorXd du;
    if (!solveTangent(rhs, du, error))
      return false;
    du += prescribedMove;
    u += du;
    (void)ds;
    for (int it = 0; it < options_.maxIterationsPerStep; ++it) {
      if (!evaluate(u, ev, true))
        return false; // the predictor inverted a cell: a smaller step
      const Balance b = BalanceOf(pb_, ev, u, to);
      lastResidual_ = b.scale > 0.0 ? b.residual.norm() / b.scale : 0.0;
      if (b.residual.norm() <= tolerance * b.scale) {
        reached.u = u;
        reached.fraction = to;
        lastIterations_ = it;
        return true;
      }
      ++report_.newtonIterations;
      if (!solveTangent(-b.residual, du, error))
        return false;
      // Backtracking: accept a step that keeps every cell valid and lowers the potential or the
      // residual (near convergence the potential's change is below round-off).
      const double slope = b.residual.dot(du);
      bool accepted = false;
      for (double alpha = 1.0; alpha >= 1.0 / 1024.0; alpha *= 0.5) {
        const Eigen::VectorXd trial = u + alpha * du;
        Evaluation tev;
        if (!evaluate(trial, tev, false))
          continue;
        const Balance tb = BalanceOf(pb_, tev, trial, to);
        if (tb.potential <= b.potential + 1e-4 * alpha * slope ||
            tb.residual.norm() < 0.5 * b.residual.norm()) {
          u = trial;
          accepted = true;
          break;
        }
      }
      if (!accepted)
        return false;
    }
    return false;
  }

  int lastIterations() const { return lastIterations_; }
  double lastResidual() const { return lastResidual_; }

private:
  bool evaluate(const Eigen::VectorXd& u, Evaluation& ev, bool withTangent) {
    StageClock clock;
    const bool ok = Evaluate(pb_, u, ev, withTangent ? &packed_ : nullptr);
    timings_[Stage::ElementStiffness].ms += clock.lapMs();
    if (ok && withTangent) {
      AssembleFromPacked(packed_.data(), pb_.pattern);
      timings_[Stage::Assembly].ms += clock.lapMs();
    }
    return ok;
  }

  // Solves the pinned tangent for a right-hand side that is zero on the prescribed DOFs. False
  // (a smaller step) when the tangent is not positive definite; `error` is set only for failures
  // a smaller step cannot mend.
  bool solveTangent(const Eigen::VectorXd& rhs, Eigen::VectorXd& du, Status& error) {
    StageClock clock;
    PinPrescribed(pb_);
    const Status factored = factor_.factorize(pb_.pattern.upper);
    timings_[Stage::Factorization].ms += clock.lapMs();
    if (!factored)
      return false;
    Eigen::MatrixXd x;
    const Status solved = factor_.solve(rhs, x);
    timings_[Stage::Solve].ms += clock.lapMs();
    if (!solved) {
      error = solved;
      return false;
    }
    du = x.col(0);
    ZeroPrescribed(pb_, du);
    return du.allFinite();
  }

  Problem& pb_;
  const LargeDeformationOptions& options_;
  CholmodFactor& factor_;
  LargeDeformationReport& report_;
  StageTimings& timings_;
  std::vector<double> packed_;
  int lastIterations_ = 0;
  double lastResidual_ = 0.0;
};

void ReportDeformation(const Problem& pb, const Eigen::VectorXd& u, LargeDeformationReport& r) {
  const TetMesh& mesh = *pb.mesh;
  r.smallestVolumeRatio = std::numeric_limits<double>::infinity();
  r.largestGreenStrain = 0.0;
  CornerDisplacements corner;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int a = 0; a < 4; ++a) {
      const int node = mesh.tets(e, a);
      corner.row(a) = pb.toGlobal(node, u.segment<3>(3 * node)).transpose();
    }
    const Eigen::Matrix3d F = DeformationGradient(pb.cells[e], corner);
    r.smallestVolumeRatio = std::min(r.smallestVolumeRatio, F.determinant());
    const Eigen::Matrix3d green = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
    const Eigen::Vector3d principal =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(green, Eigen::EigenvaluesOnly).eigenvalues();
    const double largest = principal.cwiseAbs().maxCoeff();
    if (largest > r.largestGreenStrain) {
      r.largestGreenStrain = largest;
      r.largestStrainCell = e;
    }
  }
}

// Unilateral contact at a converged state u for the load fraction s: a node in contact whose
// contact force pulls it onto the bone (a negative normal residual) lifts off, a lifted node that
// has gone into the bone comes back into contact. True when a node changed.
bool UpdateContact(Problem& pb, const Eigen::VectorXd& u, double s) {
  if (pb.liftOffDofs.empty())
    return false;
  Evaluation ev;
  if (!Evaluate(pb, u, ev, nullptr))
    return false;
  const Eigen::VectorXd reaction = ev.force - s * pb.externalLoad;
  const double forceTolerance = 1e-12 * std::max(ev.force.norm(), pb.linearForce);
  const double gapTolerance = 1e-12 * std::max(1.0, pb.target.cwiseAbs().maxCoeff());
  bool changed = false;
  for (int dof : pb.liftOffDofs) {
    if (pb.prescribed[dof] && reaction[dof] < -forceTolerance) {
      pb.prescribed[dof] = 0;
      changed = true;
    } else if (!pb.prescribed[dof] && u[dof] < s * pb.target[dof] - gapTolerance) {
      pb.prescribed[dof] = 1;
      changed = true;
    }
  }
  if (changed)
    FindPinnedEntries(pb);
  return changed;
}

// The relative residual at which lift-off's contact is updated before the final solve.
constexpr double kSettleTolerance = 1e-6;

Status LargeDeformationImpl(const PrecomputeRequest& request, const SolveInput& input,
                            const LargeDeformationOptions& options, SolveResult& result,
                            LargeDeformationReport& report) {
  StageClock total, clock;
  result = SolveResult();
  report = LargeDeformationReport();
  result.method = SolveMethod::FullReference;
  result.backend = "CPU";
  if (request.options.elementOrder != ElementOrder::Linear)
    return Status::Error("the large-deformation model supports linear (4-node) elements only");
  if (!(options.tolerance > 0.0) || !(options.initialStep > 0.0) || options.initialStep > 1.0 ||
      options.maxIterationsPerStep < 1 || options.maxStepHalvings < 0 || options.maxLoadSteps < 1 ||
      options.maxTotalIterations < 1 || options.maxContactUpdatesPerStep < 0 ||
      options.maxContactUpdates < 0)
    return Status::Error("invalid large-deformation options");
  Status status = ValidateSolveInputs(request.mesh, request.materials, request.sets);
  if (!status)
    return status;
  if (input.movableDisplacement.rows() != static_cast<Eigen::Index>(request.sets.movable.size()))
    return Status::Error("expected one ROI displacement per movable node");
  if (!input.movableDisplacement.allFinite() || !input.gravity.allFinite())
    return Status::Error("prescribed displacements or loads contain NaN or infinite values");

  Problem pb;
  status = Setup(request, input, options.slidingLiftOff, pb);
  if (!status)
    return status;
  result.timings[Stage::Separation].ms = clock.lapMs();
  CholmodFactor factor;
  // METIS on the node graph, as the linear model's factor (SparseSolver/FillReducingOrdering.h).
  FillReducingOrdering ordering;
  status = OrderNodesWithTrailing(pb.pattern.upper, 3, {}, ordering);
  if (status)
    status = factor.analyze(pb.pattern.upper, &ordering);
  if (!status)
    return status;
  result.timings[Stage::Reordering].ms = clock.lapMs();

  NewtonSolver newton(pb, options, factor, report, result.timings);
  StepState state;
  state.u = Eigen::VectorXd::Zero(3 * pb.n);
  {
    Evaluation rest;
    std::vector<double> packed;
    Evaluate(pb, state.u, rest, &packed);
    AssembleFromPacked(packed.data(), pb.pattern);
    pb.linearForce = (pb.pattern.upper.selfadjointView<Eigen::Upper>() * pb.target).norm();
    Eigen::VectorXd positions(3 * pb.n);
    for (Eigen::Index i = 0; i < pb.n; ++i)
      positions.segment<3>(3 * i) =
          pb.toLocal(static_cast<int>(i), pb.mesh->points.row(i).transpose());
    pb.unitStrainForce = (pb.pattern.upper.selfadjointView<Eigen::Upper>() * positions).norm();
  }
  double step = options.initialStep;
  int halvings = 0;
  while (state.fraction < 1.0) {
    if (report.loadSteps + report.rejectedSteps >= options.maxLoadSteps)
      return Status::Error("the large-deformation solve needed more than " +
                           std::to_string(options.maxLoadSteps) + " load steps");
    if (report.contactUpdates >= options.maxContactUpdates)
      return Status::Error("the large-deformation solve did not converge: the lift-off contact "
                           "changed " +
                           std::to_string(report.contactUpdates) +
                           " times without settling (check the sliding normals)");
    if (report.newtonIterations >= options.maxTotalIterations)
      return Status::Error("the large-deformation solve did not converge within " +
                           std::to_string(options.maxTotalIterations) + " Newton iterations");
    const double to = std::min(1.0, state.fraction + step);
    StepState reached;
    Status failure;
    // With lift-off the contact is settled on loosely converged states (it changes a few times)
    // and the last solve converges fully; a contact change after it starts the loop again.
    const double settleTolerance =
        pb.liftOffDofs.empty() ? options.tolerance : std::max(options.tolerance, kSettleTolerance);
    if (newton.step(state, to, settleTolerance, reached, failure)) {
      int updates = 0;
      bool settled = true, tight = settleTolerance == options.tolerance;
      while (true) {
        const bool changed = UpdateContact(pb, reached.u, to);
        if (!changed && tight)
          break;
        if (changed)
          ++report.contactUpdates;
        const StepState start = reached;
        tight = !changed;
        if (++updates > options.maxContactUpdatesPerStep ||
            !newton.step(start, to, tight ? options.tolerance : settleTolerance, reached,
                         failure)) {
          settled = false;
          break;
        }
      }
      if (!failure.ok)
        return failure;
      if (settled) {
        state = reached;
        ++report.loadSteps;
        if (options.progress)
          options.progress(state.fraction);
        halvings = 0;
        if (newton.lastIterations() <= 6)
          step = std::min(1.0, 2.0 * step);
        continue;
      }
      // The contact kept changing: a smaller step, starting from the contact reached so far.
    }
    if (!failure.ok)
      return failure;
    ++report.rejectedSteps;
    if (++halvings > options.maxStepHalvings) {
      std::ostringstream why;
      why << "the large-deformation solve did not converge: it reached " << 100.0 * state.fraction
          << " % of the prescribed move, and smaller load steps could not go further (a cell "
             "would invert, or the lift-off contact did not settle)";
      return Status::Error(why.str());
    }
    step *= 0.5;
  }

  ReportDeformation(pb, state.u, report);
  for (int dof : pb.liftOffDofs)
    report.liftedNodes += pb.prescribed[dof] ? 0 : 1;
  result.relativeResidual = newton.lastResidual();
  result.largestStrain = report.largestGreenStrain;
  result.invertedCells = 0;
  const Eigen::Index n = pb.n;
  RowVectors3d all(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    all.row(i) = pb.toGlobal(static_cast<int>(i), state.u.segment<3>(3 * i)).transpose();
  if (!all.allFinite())
    return Status::Error("the large-deformation solve produced non-finite values");
  result.keptDisplacement.resize(static_cast<Eigen::Index>(request.sets.kept.size()), 3);
  for (size_t k = 0; k < request.sets.kept.size(); ++k)
    result.keptDisplacement.row(static_cast<Eigen::Index>(k)) = all.row(request.sets.kept[k]);
  if (input.recoverInterior)
    result.allDisplacement = std::move(all);
  result.timings[Stage::Total].ms = total.elapsedMs();
  return Status::Ok();
}

} // namespace

Status SolveLargeDeformation(const PrecomputeRequest& request, const SolveInput& input,
                             const LargeDeformationOptions& options, SolveResult& result,
                             LargeDeformationReport& report) {
  return ReturnStatusOnException("the large-deformation solve", [&]() -> Status {
    return LargeDeformationImpl(request, input, options, result, report);
  });
}

} // namespace faceplan
