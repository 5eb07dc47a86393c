// Validation and the Separation stage: node classes, DOF layout, and the K_FF / K_FR blocks.
#include "CondensedFEM/PrecomputeStages.h"

#include "Element/ElementStiffness.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"

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

} // namespace

Status ValidatePrecomputeRequest(PrecomputeState& state) {
  const PrecomputeRequest& request = state.request;
  const PrecomputeOptions& options = request.options;
  if (options.method == SolveMethod::FullReference)
    return Status::Error("FullReference has no precompute: call SolveFullReference");
  Status status = ValidateMeshAndMaterials(request.mesh, request.materials);
  if (status)
    status = ValidateNodeSets(request.mesh, request.sets);
  if (status)
    status = CheckEveryComponentConstrained(request.mesh, request.sets.constrained);
  if (status)
    status = CheckRigidModesHeld(request.mesh, request.sets.constrained);
  if (!status)
    return status;
  if (!(options.residualTolerance > 0.0) || options.maxRefinementSteps < 0)
    return Status::Error("residualTolerance must be positive and maxRefinementSteps non-negative");
  if (options.sliverQualityThreshold > 0.0) {
    QualityReport quality;
    const std::string w =
        CheckElementQuality(request.mesh, options.sliverQualityThreshold, &quality);
    if (!w.empty())
      status.warnings.push_back(w);
    state.sys->info.sliverCells = quality.belowThreshold;
    state.sys->info.worstQuality = quality.worstQuality;
  }
  state.status = status;
  return Status::Ok();
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
  sys.kept = request.sets.kept;
  sys.movableNodes = request.sets.movable;
  state.quadratic = options.elementOrder == ElementOrder::Quadratic ||
                    options.elementOrder == ElementOrder::QuadraticNodalPressure;
  state.nodalPressure = options.elementOrder == ElementOrder::QuadraticNodalPressure;
  sys.info.elementOrder = options.elementOrder;

  // Quadratic elements: the TET10 mesh and the node sets extended to its mid-edge nodes.
  NodeSets solverSets;
  if (state.quadratic) {
    state.qmesh = MakeQuadraticMesh(mesh, options.midEdgeProjection);
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
    for (int i : request.sets.kept)
      known[i] = 1;
    for (int i : request.sets.constrained)
      known[i] = 1;
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
      if (known[mesh.tets(e, 0)] && known[mesh.tets(e, 1)] && known[mesh.tets(e, 2)] &&
          known[mesh.tets(e, 3)])
        sys.checkableCells.push_back(static_cast<int>(e));
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
  sys.kff = Eigen::Map<const SparseMatrix>(freeDofs, freeDofs, upper.outerIndexPtr()[freeDofs],
                                           upper.outerIndexPtr(), upper.innerIndexPtr(),
                                           upper.valuePtr());
  sys.kfr = upper.block(0, freeDofs, freeDofs, upper.cols() - freeDofs);
  sys.kfr.makeCompressed();
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
  info.roiDofs = 3LL * layout.roi;
  info.interiorDofs = 3LL * layout.interior;
  return Status::Ok();
}

} // namespace faceplan
