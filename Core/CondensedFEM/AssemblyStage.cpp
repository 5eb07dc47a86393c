// SPDX-License-Identifier: BSD-3-Clause
// The ElementStiffness and Assembly stages.
#include "CondensedFEM/PrecomputeStages.h"

#include "Element/NodalPressure.h"

#include <sstream>

namespace faceplan {

Status AssembleStiffness(PrecomputeState& state) {
  const PrecomputeRequest& request = state.request;
  const PrecomputeOptions& options = request.options;
  const TetMesh& mesh = request.mesh;
  const NodeLayout& layout = state.sys->layout;
  const QuadraticMesh& qmesh = state.qmesh;
  StageClock& clock = state.clock;
  // Nodal pressure: cells give the shear part; the volumetric part is added after assembly.
  const Materials cellMaterials =
      state.nodalPressure ? ShearOnlyMaterials(request.materials) : Materials();
  const Materials& stiffnessMaterials = state.nodalPressure ? cellMaterials : request.materials;

  AssemblyPattern& pattern = state.pattern;
  const int* cells = state.quadratic ? qmesh.cells.data() : mesh.tets.data();
  const Eigen::Index numCells = state.quadratic ? qmesh.cells.rows() : mesh.numTets();
  const int nodesPerCell = state.quadratic ? 10 : 4;
  // The node graph first: K_FF's ordering starts from it on its own thread (when its structure
  // follows from the cells alone) while the gather map, the element matrices and the separation
  // are made here.
  const Groups cornersOf = CornersByNode(cells, numCells, nodesPerCell, layout.dofNode,
                                         static_cast<int>(layout.meshNode.size()));
  auto lower = std::make_shared<const NodeNeighbours>(
      LowerNodeNeighbours(cells, nodesPerCell, layout.dofNode, cornersOf));
  StartEarlyOrdering(state, lower);
  const Status patternBuilt = BuildCellAssemblyPattern(cells, numCells, nodesPerCell,
                                                       layout.dofNode, cornersOf, *lower, pattern);
  if (!patternBuilt)
    return patternBuilt;
  const double patternMs = clock.lapMs();
  state.backend = options.backend ? options.backend : MakeCpuBackend();
  ComputeBackend::AssemblyTimings at;
  if (state.quadratic) {
    // The backends implement 4-node cells; 10-node cells are computed and assembled on the CPU.
    PackedElementMatrices packed;
    std::vector<long long> invalid;
    ComputePackedTet10Stiffness(qmesh, stiffnessMaterials, packed, invalid,
                                options.quadraticMeanDilatation);
    if (!invalid.empty()) {
      std::ostringstream msg;
      msg << invalid.size() << " quadratic cells have a non-positive Jacobian after the mid-edge "
          << "projection (first: cell " << invalid.front()
          << "); the projection moves mid-edge nodes too far for these cells";
      return Status::Error(msg.str());
    }
    at.elementStiffnessMs = clock.lapMs();
    AssembleFromPacked(packed.data(), pattern);
    at.assemblyMs = clock.lapMs();
  } else if (const Status assembled =
                 state.backend->assembleStiffness(mesh, request.materials, pattern, at);
             !assembled) {
    state.status.warnings.push_back(state.backend->name() + " backend failed (" +
                                    assembled.message + "); used the CPU");
    state.backend = MakeCpuBackend();
    at = {};
    const Status onCpu = state.backend->assembleStiffness(mesh, request.materials, pattern, at);
    if (!onCpu)
      return onCpu;
  }
  if (state.nodalPressure) { // the volumetric part, added to the shear part assembled above
    clock.lapMs();
    const Status added = AddNodalPressureStiffness(
        pattern.upper, qmesh.points, qmesh.cells.data(), qmesh.cells.rows(), 10, request.materials,
        layout.dofNode, static_cast<int>(layout.meshNode.size()));
    if (!added)
      return added;
    at.assemblyMs += clock.lapMs();
  }
  state.sys->backendName = state.backend->name();
  state.time(Stage::ElementStiffness).ms = at.elementStiffnessMs;
  state.time(Stage::Assembly).ms = patternMs + at.assemblyMs;
  clock.lapMs();
  state.report(0.15, "assembly");
  return state.cancelled() ? Status::Error("cancelled") : Status::Ok();
}

} // namespace faceplan
