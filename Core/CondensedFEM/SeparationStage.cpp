// SPDX-License-Identifier: BSD-3-Clause
// Validation and the Separation stage: node classes, DOF layout, and the K_FF / K_FR blocks.
#include "CondensedFEM/PrecomputeStages.h"

#include "CondensedFEM/RigidSegments.h"
#include "Element/ElementStiffness.h"
#include "Mesh/InputValidation.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"

#include "Common/ExceptionBoundary.h"

#include <Eigen/Geometry>

namespace faceplan {

namespace {

// Lumped rho * V / 4 per free node: the consistent gravity load of a linear tetrahedron.
Eigen::VectorXd FreeNodeMass(const TetMesh& mesh, const Materials& materials,
                             const NodeLayout& layout) {
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(layout.freeNodes());
  if (materials.density.size() == 0)
    return mass;
  TetCorners corners;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    const double rho = materials.rho(e);
    if (rho == 0.0)
      continue;
    for (int k = 0; k < 4; ++k)
      corners.row(k) = mesh.points.row(mesh.tets(e, k));
    const double quarter = rho * TetVolume(corners) / 4.0;
    for (int k = 0; k < 4; ++k) {
      const int pos = layout.dofNode[mesh.tets(e, k)];
      if (pos >= 0 && pos < layout.freeNodes())
        mass[pos] += quarter;
    }
  }
  return mass;
}

// Consistent unit-body-force load per free node of a quadratic mesh (integral of rho N_a).
Eigen::VectorXd FreeNodeMassQuadratic(const QuadraticMesh& mesh, const Materials& materials,
                                      const NodeLayout& layout) {
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(layout.freeNodes());
  if (materials.density.size() == 0)
    return mass;
  Tet10Nodes nodes;
  for (Eigen::Index e = 0; e < mesh.cells.rows(); ++e) {
    const double rho = materials.rho(e);
    if (rho == 0.0)
      continue;
    for (int k = 0; k < 10; ++k)
      nodes.row(k) = mesh.points.row(mesh.cells(e, k));
    const Eigen::Matrix<double, 10, 1> integral = Tet10ShapeIntegrals(nodes);
    for (int k = 0; k < 10; ++k) {
      const int pos = layout.dofNode[mesh.cells(e, k)];
      if (pos >= 0 && pos < layout.freeNodes())
        mass[pos] += rho * integral[k];
    }
  }
  return mass;
}

// The caller's node sets extended to the mid-edge nodes of a quadratic mesh. `derived` receives,
// for each mid-edge ROI node (appended after the caller's movable nodes), its ends' positions in
// the caller's movable list (-1 for a fixed end).
NodeSets QuadraticNodeSets(const QuadraticMesh& q, const NodeSets& sets,
                           std::vector<std::array<int, 2>>& derived) {
  const Eigen::Index n = q.numCorners;
  std::vector<char> constrained(n, 0);
  std::vector<int> movablePos(n, -1);
  for (int i : sets.constrained)
    constrained[i] = 1;
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (movablePos[sets.movable[k]] < 0)
      movablePos[sets.movable[k]] = static_cast<int>(k);
  NodeSets out = sets;
  derived.clear();
  for (size_t e = 0; e < q.edges.size(); ++e) {
    const int a = q.edges[e][0], b = q.edges[e][1];
    if (!constrained[a] || !constrained[b])
      continue; // interior: kept nodes are corners only
    const int node = static_cast<int>(n + static_cast<Eigen::Index>(e));
    out.constrained.push_back(node);
    if (movablePos[a] >= 0 || movablePos[b] >= 0) {
      out.movable.push_back(node);
      derived.push_back({movablePos[a], movablePos[b]});
    }
  }
  return out;
}

void DescribeSlidingNodes(const NodeSets& sets, CondensedSystem& sys) {
  const NodeLayout& layout = sys.layout;
  sys.slidingOfPosition.assign(layout.meshNode.size(), -1);
  std::vector<int> roiDofOfNode(sys.numMeshNodes, -1);
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (layout.slidingRoiDof[k] >= 0)
      roiDofOfNode[sets.movable[k]] = layout.slidingRoiDof[k];
  for (size_t s = 0; s < sets.sliding.size(); ++s) {
    const int node = sets.sliding[s], pos = layout.dofNode[node];
    if (pos < 0)
      continue; // in no cell
    sys.slidingOfPosition[pos] = static_cast<int>(sys.slidingFrame.size());
    sys.slidingFrame.push_back(NormalFrame(sets.slidingNormal[s]));
    sys.slidingRoiDof.push_back(roiDofOfNode[node]);
  }
}

// The ROI DOF values as a linear map of the caller's movable displacements (3 per node,
// node-major). The layout's movable list may extend the caller's with `derived` mid-edge nodes.
// A repeated movable id takes its last occurrence's value.
SparseMatrix MovableToRoi(const NodeLayout& layout, const std::vector<std::array<int, 2>>& derived,
                          const NodeSets& callerSets) {
  const Eigen::Index movable = static_cast<Eigen::Index>(callerSets.movable.size());
  std::vector<int> source(layout.roiDofs(), -1); // ROI DOF group -> caller movable index
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index k = 0; k < movable; ++k) {
    if (layout.roiPosition[k] >= 0)
      source[3 * layout.roiPosition[k]] = static_cast<int>(k);
    if (layout.slidingRoiDof[k] >= 0)
      source[layout.slidingRoiDof[k]] = static_cast<int>(k);
  }
  std::vector<Eigen::Vector3d> normalOf(layout.dofNode.size(), Eigen::Vector3d::Zero());
  for (size_t s = 0; s < callerSets.sliding.size(); ++s)
    normalOf[callerSets.sliding[s]] = callerSets.slidingNormal[s];
  for (Eigen::Index k = 0; k < movable; ++k) {
    const int pos = layout.roiPosition[k], dof = layout.slidingRoiDof[k];
    if (pos >= 0 && source[3 * pos] == k)
      for (int i = 0; i < 3; ++i)
        entries.emplace_back(3 * pos + i, 3 * k + i, 1.0);
    if (dof >= 0 && source[dof] == k)
      for (int i = 0; i < 3; ++i)
        entries.emplace_back(dof, 3 * k + i, normalOf[callerSets.movable[k]][i]);
  }
  for (size_t d = 0; d < derived.size(); ++d) {
    const int pos = layout.roiPosition[movable + static_cast<Eigen::Index>(d)];
    if (pos < 0)
      continue;
    for (int end : derived[d])
      if (end >= 0)
        for (int i = 0; i < 3; ++i)
          entries.emplace_back(3 * pos + i, 3 * end + i, 0.5);
  }
  SparseMatrix map(layout.roiDofs(), 3 * movable);
  map.setFromTriplets(entries.begin(), entries.end());
  return map;
}

// K' = T^T K T with T the sliding nodes' frames, then split: the sliding normal DOFs are pinned in
// K_FF (their row and column cleared, the diagonal kept so the scaling stays), and their columns
// join K_FR as the ROI DOFs of their prescribed normal values.
void SeparateRotatedBlocks(const SparseMatrix& upper, CondensedSystem& sys) {
  const NodeLayout& layout = sys.layout;
  const Eigen::Index n = upper.rows(), freeDofs = 3 * layout.freeNodes();
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<int> pinned(n, -2); // -2: not pinned; -1: pinned at zero; else its ROI DOF
  std::vector<char> rotated(layout.meshNode.size(), 0);
  for (size_t pos = 0; pos < sys.slidingOfPosition.size(); ++pos) {
    const int s = sys.slidingOfPosition[pos];
    if (s < 0)
      continue;
    rotated[pos] = 1;
    pinned[3 * pos] = sys.slidingRoiDof[s];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        entries.emplace_back(3 * pos + a, 3 * pos + b, sys.slidingFrame[s](a, b));
  }
  for (size_t pos = 0; pos < rotated.size(); ++pos)
    if (!rotated[pos])
      for (int a = 0; a < 3; ++a)
        entries.emplace_back(3 * pos + a, 3 * pos + a, 1.0);
  SparseMatrix frames(n, n);
  frames.setFromTriplets(entries.begin(), entries.end());
  const SparseMatrix full = upper.selfadjointView<Eigen::Upper>();
  const SparseMatrix framesT = frames.transpose();
  const SparseMatrix turned = framesT * full * frames;

  std::vector<Eigen::Triplet<double>> ff, fr;
  for (Eigen::Index j = 0; j < turned.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(turned, j); it; ++it) {
      const Eigen::Index i = it.row();
      if (i >= freeDofs)
        continue;
      if (j < freeDofs) {
        if (i > j)
          continue;
        if ((pinned[i] != -2 || pinned[j] != -2) && i != j) {
          if (pinned[j] >= 0 && pinned[i] == -2)
            fr.emplace_back(i, pinned[j], it.value());
          if (pinned[i] >= 0 && pinned[j] == -2)
            fr.emplace_back(j, pinned[i], it.value());
          continue;
        }
        ff.emplace_back(i, j, it.value());
      } else if (pinned[i] == -2) {
        fr.emplace_back(i, j - freeDofs, it.value());
      }
    }
  sys.kff.resize(freeDofs, freeDofs);
  sys.kff.setFromTriplets(ff.begin(), ff.end());
  sys.kfr.resize(freeDofs, layout.roiDofs());
  sys.kfr.setFromTriplets(fr.begin(), fr.end());
}

} // namespace

Status ValidatePrecomputeRequest(PrecomputeState& state) {
  const PrecomputeRequest& request = state.request;
  const PrecomputeOptions& options = request.options;
  if (options.method == SolveMethod::FullReference)
    return Status::Error("FullReference has no precompute: call SolveFullReference");
  Status status = ValidateSolveInputs(request.mesh, request.materials, request.sets);
  if (!status)
    return status;
  if (options.method == SolveMethod::RigidSegments && SegmentCount(request.sets) == 0)
    return Status::Error(
        "RigidSegments needs segment ids (NodeSets::movableSegment) of at least 1");
  if (!request.sets.sliding.empty() && options.elementOrder != ElementOrder::Linear)
    return Status::Error("sliding nodes need linear elements (ElementOrder::Linear)");
  if (!(options.residualTolerance > 0.0) || options.maxRefinementSteps < 0)
    return Status::Error("residualTolerance must be positive and maxRefinementSteps non-negative");
  state.status = status;
  state.meshCheckWarningsAt = status.warnings.size();
  // The checks on the shared faces grow with the mesh: they run beside the separation, assembly
  // and ordering, which the inputs checked above keep safe.
  const TetMesh* mesh = &request.mesh;
  const std::vector<int>* constrained = &request.sets.constrained;
  const double sliverThreshold = options.sliverQualityThreshold;
  state.meshChecks = std::async(std::launch::async, [mesh, constrained, sliverThreshold]() {
    MeshChecks out;
    StageClock clock;
    out.status = ReturnStatusOnException("the mesh checks", [&]() -> Status {
      const std::vector<SharedFace> shared = SharedFaces(*mesh);
      Status checked = CheckRigidModesHeld(*mesh, *constrained, shared);
      if (!checked)
        return checked;
      if (sliverThreshold > 0.0) {
        QualityReport quality;
        if (const std::string w = CheckElementQuality(*mesh, sliverThreshold, &quality); !w.empty())
          checked.warnings.push_back(w);
        out.sliverCells = quality.belowThreshold;
        out.worstQuality = quality.worstQuality;
      }
      FoldReport folds;
      if (const std::string w = CheckFoldedFaces(*mesh, shared, &folds); !w.empty())
        checked.warnings.push_back(w);
      out.foldedFaces = folds.foldedFaces;
      return checked;
    });
    out.ms = clock.elapsedMs();
    return out;
  });
  return Status::Ok();
}

Status FinishMeshChecks(PrecomputeState& state) {
  if (!state.meshChecks.valid())
    return Status::Ok();
  const MeshChecks checks = state.meshChecks.get();
  // Separation, where the checks used to run, holds the wait for them (the rows add up to the
  // precompute's time); their own time is in SystemInfo::meshChecksThreadMs.
  state.time(Stage::Separation).ms += state.clock.lapMs();
  state.sys->info.meshChecksThreadMs = checks.ms;
  if (!checks.status)
    return checks.status;
  // Their warnings where the validation used to put them, before the later stages' ones.
  state.status.warnings.insert(state.status.warnings.begin() + state.meshCheckWarningsAt,
                               checks.status.warnings.begin(), checks.status.warnings.end());
  SystemInfo& info = state.sys->info;
  info.sliverCells = checks.sliverCells;
  info.worstQuality = checks.worstQuality;
  info.foldedFaces = checks.foldedFaces;
  return state.cancelled() ? Status::Error("cancelled") : Status::Ok();
}

Status SeparateNodes(PrecomputeState& state) {
  const PrecomputeRequest& request = state.request;
  const PrecomputeOptions& options = request.options;
  const TetMesh& mesh = request.mesh;
  CondensedSystem& sys = *state.sys;
  sys.residualTolerance = options.residualTolerance;
  sys.maxRefinementSteps = options.maxRefinementSteps;
  sys.strainWarningLimit = options.strainWarningLimit;
  sys.numOutputNodes = mesh.numPoints();
  sys.cornerMesh = mesh;
  sys.meshExtent =
      mesh.numPoints() > 0
          ? (mesh.points.colwise().maxCoeff() - mesh.points.colwise().minCoeff()).norm()
          : 1.0;
  sys.kept = request.sets.kept;
  sys.movableNodes = request.sets.movable;
  state.quadratic = options.elementOrder == ElementOrder::Quadratic ||
                    options.elementOrder == ElementOrder::QuadraticNodalPressure;
  state.nodalPressure = options.elementOrder == ElementOrder::QuadraticNodalPressure;
  sys.info.elementOrder = options.elementOrder;

  // Quadratic elements: the TET10 mesh and the node sets extended to its mid-edge nodes.
  NodeSets solverSets;
  if (state.quadratic) {
    const Status built = MakeQuadraticMesh(mesh, state.qmesh, options.midEdgeProjection);
    if (!built)
      return built;
    if (!state.qmesh.points.allFinite())
      return Status::Error("the mid-edge projection returned non-finite coordinates");
    solverSets = QuadraticNodeSets(state.qmesh, request.sets, sys.derivedMovable);
  }
  const NodeSets& sets = state.quadratic ? solverSets : request.sets;
  sys.numMeshNodes = state.quadratic ? state.qmesh.points.rows() : mesh.numPoints();
  sys.info.solverNodes = sys.numMeshNodes;
  {
    std::vector<char> used(sys.numMeshNodes, 0);
    if (state.quadratic) {
      for (Eigen::Index k = 0; k < state.qmesh.cells.size(); ++k)
        used[state.qmesh.cells.data()[k]] = 1;
    } else {
      for (Eigen::Index k = 0; k < mesh.tets.size(); ++k)
        used[mesh.tets.data()[k]] = 1;
    }
    sys.layout = MakeLayout(used, sets);
  }
  {
    // Cells a kept-only solve can check for large strain: every corner kept or constrained.
    std::vector<char> known(mesh.numPoints(), 0);
    for (int i : request.sets.constrained)
      known[i] = 1;
    for (int i : request.sets.sliding)
      known[i] = 0; // tangential part solved, not given
    for (int i : request.sets.kept)
      known[i] = 1;
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
      if (known[mesh.tets(e, 0)] && known[mesh.tets(e, 1)] && known[mesh.tets(e, 2)] &&
          known[mesh.tets(e, 3)])
        sys.checkableCells.push_back(static_cast<int>(e));
  }
  DescribeSlidingNodes(request.sets, sys);
  sys.keptIsFreeBlock = true;
  for (size_t k = 0; k < sys.kept.size() && sys.keptIsFreeBlock; ++k)
    sys.keptIsFreeBlock = sys.layout.dofNode[sys.kept[k]] == static_cast<int>(k) &&
                          (sys.slidingOfPosition.empty() || sys.slidingOfPosition[k] < 0);
  sys.movableToRoi = MovableToRoi(sys.layout, sys.derivedMovable, request.sets);
  sys.segments = SegmentCount(request.sets);
  if (sys.segments > 0) {
    sys.segmentSets.movable = request.sets.movable;
    sys.segmentSets.movableSegment = request.sets.movableSegment;
    sys.segmentToRoi = sys.movableToRoi * SegmentBasis(mesh.points, request.sets);
  }
  state.time(Stage::Separation).ms = state.clock.lapMs();
  state.report(0.05, "separation");
  return state.cancelled() ? Status::Error("cancelled") : Status::Ok();
}

Status SeparateBlocks(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  const NodeLayout& layout = sys.layout;
  // Blocks of the assembled upper triangle: free columns first, then ROI columns.
  const int freeDofs = 3 * layout.freeNodes();
  const SparseMatrix& upper = state.pattern.upper;
  if (sys.slidingFrame.empty()) {
    sys.kff = Eigen::Map<const SparseMatrix>(freeDofs, freeDofs, upper.outerIndexPtr()[freeDofs],
                                             upper.outerIndexPtr(), upper.innerIndexPtr(),
                                             upper.valuePtr());
    sys.kfr = upper.block(0, freeDofs, freeDofs, upper.cols() - freeDofs);
  } else {
    SeparateRotatedBlocks(upper, sys);
  }
  sys.kfr.makeCompressed();
  const SolveMethod requested = state.request.options.method;
  if (sys.segments > 0 &&
      (requested == SolveMethod::Auto || requested == SolveMethod::RigidSegments))
    state.segmentCoupling = sys.kfr * sys.segmentToRoi;
  state.pattern = AssemblyPattern(); // free the global pattern early
  sys.nodeMass = state.quadratic
                     ? FreeNodeMassQuadratic(state.qmesh, state.request.materials, layout)
                     : FreeNodeMass(state.request.mesh, state.request.materials, layout);
  state.qmesh = QuadraticMesh();
  state.time(Stage::Separation).ms += state.clock.lapMs();

  SystemInfo& info = sys.info;
  info.backend = sys.backendName;
  info.freeDofs = freeDofs;
  info.keptDofs = 3LL * layout.keptFree;
  info.roiDofs = layout.roiDofs();
  info.interiorDofs = 3LL * layout.interior;
  return Status::Ok();
}

} // namespace faceplan
