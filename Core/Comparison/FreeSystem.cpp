// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/FreeSystem.h"

#include "Common/ExceptionBoundary.h"
#include "CondensedFEM/NodeLayout.h"
#include "Element/ElementStiffness.h"
#include "Mesh/InputValidation.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"

namespace faceplan {

namespace {

// The same numbering as the condensed solver's (NodeLayout).
void MakeFreeLayout(const TetMesh& mesh, const NodeSets& sets, FreeSystem& s) {
  std::vector<char> used(mesh.numPoints(), 0);
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int k = 0; k < 4; ++k)
      used[mesh.tets(e, k)] = 1;
  NodeLayout layout = MakeLayout(used, sets);
  s.dofNode = std::move(layout.dofNode);
  s.meshNode = std::move(layout.meshNode);
  s.keptFree = layout.keptFree;
  s.interior = layout.interior;
  s.roi = layout.roi;
  s.roiPosition = std::move(layout.roiPosition);
}

} // namespace

Status BuildFreeSystem(const PrecomputeRequest& request, FreeSystem& s) {
  return ReturnStatusOnException("assembling the free system", [&]() -> Status {
    s = FreeSystem();
    Status status = ValidateSolveInputs(request.mesh, request.materials, request.sets);
    if (!status)
      return status;
    s.numMeshNodes = request.mesh.numPoints();
    s.kept = request.sets.kept;
    MakeFreeLayout(request.mesh, request.sets, s);
    StageClock clock;
    AssemblyPattern pattern;
    status =
        BuildAssemblyPattern(request.mesh, s.dofNode, static_cast<int>(s.meshNode.size()), pattern);
    if (!status)
      return status;
    const double patternMs = clock.lapMs();
    PackedElementMatrices packed;
    ComputePackedElementStiffness(request.mesh, request.materials, packed);
    s.elementStiffnessMs = clock.lapMs();
    AssembleFromPacked(packed.data(), pattern);
    const int f = s.freeDofs();
    const SparseMatrix& upper = pattern.upper;
    s.kff = Eigen::Map<const SparseMatrix>(f, f, upper.outerIndexPtr()[f], upper.outerIndexPtr(),
                                           upper.innerIndexPtr(), upper.valuePtr());
    s.kfr = upper.block(0, f, f, upper.cols() - f);
    s.kfr.makeCompressed();
    s.assemblyMs = patternMs + clock.lapMs();
    return status;
  });
}

Status RoiVector(const FreeSystem& s, const RowVectors3d& movable, Eigen::VectorXd& roi) {
  if (movable.rows() != static_cast<Eigen::Index>(s.roiPosition.size()))
    return Status::Error("expected " + std::to_string(s.roiPosition.size()) +
                         " ROI displacements, got " + std::to_string(movable.rows()));
  if (!movable.allFinite())
    return Status::Error("prescribed displacements contain NaN or infinite values");
  roi = Eigen::VectorXd::Zero(3 * s.roi);
  for (size_t k = 0; k < s.roiPosition.size(); ++k)
    if (s.roiPosition[k] >= 0)
      roi.segment<3>(3 * s.roiPosition[k]) = movable.row(k).transpose();
  return Status::Ok();
}

Eigen::VectorXd FreeRightHandSide(const FreeSystem& s, const Eigen::VectorXd& roi) {
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(s.freeDofs());
  if (roi.size() > 0)
    rhs.noalias() -= s.kfr * roi;
  return rhs;
}

namespace {
Eigen::RowVector3d ValueOf(const FreeSystem& s, int node, const Eigen::VectorXd& freeValues,
                           const Eigen::VectorXd& roi) {
  const int pos = s.dofNode[node];
  if (pos < 0)
    return Eigen::RowVector3d::Zero();
  if (pos >= s.freeNodes())
    return roi.segment<3>(3 * (pos - s.freeNodes())).transpose();
  return freeValues.segment<3>(3 * pos).transpose();
}
} // namespace

RowVectors3d KeptDisplacement(const FreeSystem& s, const Eigen::VectorXd& freeValues,
                              const Eigen::VectorXd& roi) {
  RowVectors3d out(static_cast<Eigen::Index>(s.kept.size()), 3);
  for (size_t k = 0; k < s.kept.size(); ++k)
    out.row(k) = ValueOf(s, s.kept[k], freeValues, roi);
  return out;
}

RowVectors3d AllDisplacement(const FreeSystem& s, const Eigen::VectorXd& freeValues,
                             const Eigen::VectorXd& roi) {
  RowVectors3d out(s.numMeshNodes, 3);
  for (Eigen::Index i = 0; i < s.numMeshNodes; ++i)
    out.row(i) = ValueOf(s, static_cast<int>(i), freeValues, roi);
  return out;
}

double FreeRelativeResidual(const FreeSystem& s, const Eigen::VectorXd& x,
                            const Eigen::VectorXd& b) {
  const double bn = b.norm();
  const Eigen::VectorXd r = s.kff.selfadjointView<Eigen::Upper>() * x - b;
  return bn > 0.0 ? r.norm() / bn : x.norm();
}

} // namespace faceplan
