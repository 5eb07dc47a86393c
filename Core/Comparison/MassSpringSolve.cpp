// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/MassSpringSolve.h"

#include "Common/ExceptionBoundary.h"
#include "Element/ElementStiffness.h"
#include "Mesh/InputValidation.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"

#include <map>

namespace faceplan {

Status MassSpringModel::build(const PrecomputeRequest& request) {
  return ReturnStatusOnException("building the mass-spring model", [&]() -> Status {
    ready_ = false;
    const TetMesh& mesh = request.mesh;
    Status status = ValidateSolveInputs(mesh, request.materials, request.sets);
    if (!status)
      return status;
    StageClock clock;
    const Eigen::Index n = mesh.numPoints();
    numNodes_ = n;
    kept_ = request.sets.kept;
    std::vector<char> constrained(n, 0), used(n, 0);
    for (int i : request.sets.constrained)
      constrained[i] = 1;
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
      for (int k = 0; k < 4; ++k)
        used[mesh.tets(e, k)] = 1;
    freeIndex_.assign(n, -1);
    prescribedIndex_.assign(n, -1);
    numFree_ = numPrescribed_ = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!used[i])
        continue;
      if (constrained[i])
        prescribedIndex_[i] = numPrescribed_++;
      else
        freeIndex_[i] = numFree_++;
    }
    movableToPrescribed_.assign(request.sets.movable.size(), -1);
    for (size_t k = 0; k < request.sets.movable.size(); ++k)
      movableToPrescribed_[k] = prescribedIndex_[request.sets.movable[k]];

    // Edge stiffness: E * sum of incident tet volumes / L^2.
    std::map<std::pair<int, int>, double> edgeStiffness;
    TetCorners corners;
    static const int edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
      for (int k = 0; k < 4; ++k)
        corners.row(k) = mesh.points.row(mesh.tets(e, k));
      const double volume = TetVolume(corners);
      for (const auto& edge : edges) {
        int a = mesh.tets(e, edge[0]), b = mesh.tets(e, edge[1]);
        if (a > b)
          std::swap(a, b);
        edgeStiffness[{a, b}] += request.materials.E(e) * volume;
      }
    }
    springs_ = static_cast<long long>(edgeStiffness.size());
    std::vector<Eigen::Triplet<double>> ff, fp;
    auto addBlock = [&](int na, int nb, const Eigen::Matrix3d& block) {
      // Block (na, nb) of the global matrix, sorted into K_FF (upper) and K_FP.
      const int fa = freeIndex_[na], fb = freeIndex_[nb], pb = prescribedIndex_[nb];
      if (fa < 0)
        return;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          if (fb >= 0) {
            if (3 * fa + i <= 3 * fb + j)
              ff.emplace_back(3 * fa + i, 3 * fb + j, block(i, j));
          } else if (pb >= 0) {
            fp.emplace_back(3 * fa + i, 3 * pb + j, block(i, j));
          }
        }
    };
    for (const auto& [edge, volumeTimesE] : edgeStiffness) {
      const Eigen::Vector3d d =
          (mesh.points.row(edge.second) - mesh.points.row(edge.first)).transpose();
      const double length2 = d.squaredNorm();
      const Eigen::Matrix3d block = (volumeTimesE / length2) * (d * d.transpose()) / length2;
      addBlock(edge.first, edge.first, block);
      addBlock(edge.second, edge.second, block);
      addBlock(edge.first, edge.second, -block);
      addBlock(edge.second, edge.first, -block);
    }
    kffUpper_.resize(3 * numFree_, 3 * numFree_);
    kffUpper_.setFromTriplets(ff.begin(), ff.end());
    kfp_.resize(3 * numFree_, 3 * numPrescribed_);
    kfp_.setFromTriplets(fp.begin(), fp.end());
    buildMs_ = clock.lapMs();
    if (numFree_ > 0) {
      status = factor_.analyze(kffUpper_);
      if (status)
        status = factor_.factorize(kffUpper_);
      if (!status)
        return Status::Error("mass-spring stiffness: " + status.message);
    }
    factorizeMs_ = clock.lapMs();
    ready_ = true;
    return Status::Ok();
  });
}

Status MassSpringModel::solve(const RowVectors3d& movable, RowVectors3d& kept,
                              RowVectors3d* all) const {
  return ReturnStatusOnException("the mass-spring solve", [&]() -> Status {
    if (!ready_)
      return Status::Error("mass-spring solve before a successful build");
    if (movable.rows() != static_cast<Eigen::Index>(movableToPrescribed_.size()))
      return Status::Error("expected one ROI displacement per movable node");
    Eigen::VectorXd up = Eigen::VectorXd::Zero(3 * numPrescribed_);
    for (size_t k = 0; k < movableToPrescribed_.size(); ++k)
      if (movableToPrescribed_[k] >= 0)
        up.segment<3>(3 * movableToPrescribed_[k]) = movable.row(k).transpose();
    Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * numFree_);
    if (numFree_ > 0) {
      const Eigen::VectorXd rhs = -(kfp_ * up);
      Eigen::MatrixXd solution;
      Status s = factor_.solve(rhs, solution);
      if (!s)
        return s;
      x = solution.col(0);
    }
    auto valueOf = [&](int node) -> Eigen::RowVector3d {
      if (freeIndex_[node] >= 0)
        return x.segment<3>(3 * freeIndex_[node]).transpose();
      if (prescribedIndex_[node] >= 0)
        return up.segment<3>(3 * prescribedIndex_[node]).transpose();
      return Eigen::RowVector3d::Zero();
    };
    kept.resize(static_cast<Eigen::Index>(kept_.size()), 3);
    for (size_t k = 0; k < kept_.size(); ++k)
      kept.row(k) = valueOf(kept_[k]);
    if (all) {
      all->resize(numNodes_, 3);
      for (Eigen::Index i = 0; i < numNodes_; ++i)
        all->row(i) = valueOf(static_cast<int>(i));
    }
    if (!kept.allFinite())
      return Status::Error("mass-spring solve produced non-finite values");
    return Status::Ok();
  });
}

} // namespace faceplan
