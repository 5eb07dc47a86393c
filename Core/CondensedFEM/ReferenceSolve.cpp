// SPDX-License-Identifier: BSD-3-Clause
// The paper's "traditional FEM": the whole system in the mesh's own numbering, no separation into
// kept/interior/ROI blocks and no cache. Prescribed DOFs are eliminated element by element, so
// this path shares only the element stiffness with the condensed one and checks the rest.
#include "Common/ExceptionBoundary.h"
#include "CondensedFEM/CondensedFEM.h"
#include "Element/ElementStiffness.h"
#include "Mesh/InputValidation.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"
#include "SparseSolver/CholmodFactor.h"

#include <cmath>
#include <numeric>

namespace faceplan {

namespace {

Status ReferenceImpl(const PrecomputeRequest& request, const SolveInput& input,
                     SolveResult& result) {
  StageClock total, clock;
  const TetMesh& mesh = request.mesh;
  const NodeSets& sets = request.sets;
  result = SolveResult();
  result.method = SolveMethod::FullReference;
  result.backend = "CPU";
  Status status = ValidateSolveInputs(mesh, request.materials, sets);
  if (!status)
    return status;
  if (!sets.sliding.empty())
    return Status::Error(
        "the reference solve ties every constrained node: it does not model sliding nodes");
  if (input.movableDisplacement.rows() != static_cast<Eigen::Index>(sets.movable.size()))
    return Status::Error("expected one ROI displacement per movable node");
  if (!input.movableDisplacement.allFinite())
    return Status::Error("prescribed displacements contain NaN or infinite values");

  // Prescribed values in mesh numbering; free nodes numbered in mesh order.
  const Eigen::Index n = mesh.numPoints();
  RowVectors3d prescribed = RowVectors3d::Zero(n, 3);
  std::vector<char> isConstrained(n, 0), used(n, 0);
  for (int id : sets.constrained)
    isConstrained[id] = 1;
  for (size_t k = 0; k < sets.movable.size(); ++k)
    prescribed.row(sets.movable[k]) = input.movableDisplacement.row(k);
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int k = 0; k < 4; ++k)
      used[mesh.tets(e, k)] = 1;
  std::vector<int> freeIndex(n, -1);
  int numFree = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (used[i] && !isConstrained[i])
      freeIndex[i] = numFree++;
  result.timings[Stage::Separation].ms = clock.lapMs();

  AssemblyPattern pattern;
  const Status patternBuilt = BuildAssemblyPattern(mesh, freeIndex, numFree, pattern);
  if (!patternBuilt)
    return patternBuilt;
  PackedElementMatrices packed;
  ComputePackedElementStiffness(mesh, request.materials, packed);
  result.timings[Stage::ElementStiffness].ms = clock.lapMs();
  AssembleFromPacked(packed.data(), pattern);
  result.timings[Stage::Assembly].ms = clock.lapMs();

  // Right-hand side: loads minus the prescribed displacements' element forces.
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(3 * numFree);
  TetCorners corners;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    bool anyFree = false, anyPrescribed = false;
    for (int k = 0; k < 4; ++k) {
      const int node = mesh.tets(e, k);
      anyFree |= freeIndex[node] >= 0;
      anyPrescribed |= isConstrained[node] && prescribed.row(node).squaredNorm() > 0.0;
    }
    if (!anyFree || !anyPrescribed)
      continue;
    for (int k = 0; k < 4; ++k)
      corners.row(k) = mesh.points.row(mesh.tets(e, k));
    const ElementMatrix ke = TetStiffness(corners, request.materials.E(e), request.materials.nu(e));
    Eigen::Matrix<double, 12, 1> ue = Eigen::Matrix<double, 12, 1>::Zero();
    for (int k = 0; k < 4; ++k)
      if (isConstrained[mesh.tets(e, k)])
        ue.segment<3>(3 * k) = prescribed.row(mesh.tets(e, k)).transpose();
    const Eigen::Matrix<double, 12, 1> fe = ke * ue;
    for (int k = 0; k < 4; ++k) {
      const int f = freeIndex[mesh.tets(e, k)];
      if (f >= 0)
        rhs.segment<3>(3 * f) -= fe.segment<3>(3 * k);
    }
  }
  result.timings[Stage::BoundaryCondition].ms = clock.lapMs();
  if (input.nodalLoads.size() > 0) {
    if (input.nodalLoads.rows() != n)
      return Status::Error("nodal loads must have one row per mesh point");
    for (Eigen::Index i = 0; i < n; ++i)
      if (freeIndex[i] >= 0)
        rhs.segment<3>(3 * freeIndex[i]) += input.nodalLoads.row(i).transpose();
  }
  if (input.gravity.squaredNorm() > 0.0) {
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
      for (int k = 0; k < 4; ++k)
        corners.row(k) = mesh.points.row(mesh.tets(e, k));
      const double quarter = request.materials.rho(e) * TetVolume(corners) / 4.0;
      for (int k = 0; k < 4; ++k) {
        const int f = freeIndex[mesh.tets(e, k)];
        if (f >= 0)
          rhs.segment<3>(3 * f) += quarter * input.gravity;
      }
    }
  }
  result.timings[Stage::Load].ms = clock.lapMs();

  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * numFree);
  if (numFree > 0) {
    CholmodFactor factor;
    status = factor.analyze(pattern.upper);
    if (!status)
      return status;
    result.timings[Stage::Reordering].ms = clock.lapMs();
    status = factor.factorize(pattern.upper);
    if (!status)
      return status;
    result.timings[Stage::Factorization].ms = clock.lapMs();
    Eigen::MatrixXd solution;
    status = factor.solve(rhs, solution);
    if (!status)
      return status;
    x = solution.col(0);
    result.timings[Stage::Solve].ms = clock.lapMs();
    const double rhsNorm = rhs.norm();
    result.relativeResidual =
        rhsNorm > 0 ? (pattern.upper.selfadjointView<Eigen::Upper>() * x - rhs).norm() / rhsNorm
                    : x.norm();
  }

  RowVectors3d all = prescribed;
  for (Eigen::Index i = 0; i < n; ++i)
    if (freeIndex[i] >= 0)
      all.row(i) = x.segment<3>(3 * freeIndex[i]).transpose();
    else if (!isConstrained[i])
      all.row(i).setZero();
  result.keptDisplacement.resize(static_cast<Eigen::Index>(sets.kept.size()), 3);
  for (size_t k = 0; k < sets.kept.size(); ++k)
    result.keptDisplacement.row(k) = all.row(sets.kept[k]);
  if (input.recoverInterior)
    result.allDisplacement = all;
  if (!all.allFinite() || !std::isfinite(result.relativeResidual))
    return Status::Error("the reference solve produced non-finite values");
  result.timings[Stage::Total].ms = total.elapsedMs();
  return Status::Ok();
}

} // namespace

Status SolveFullReference(const PrecomputeRequest& request, const SolveInput& input,
                          SolveResult& result) {
  return ReturnStatusOnException("the reference solve",
                                 [&]() -> Status { return ReferenceImpl(request, input, result); });
}

} // namespace faceplan
