// SPDX-License-Identifier: BSD-3-Clause
// Patch test and rigid motion on generated shells: a linear field prescribed on the boundary is
// reproduced exactly inside; a rigid motion produces no strain and no reaction.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedFEM.h"
#include "Element/ElementStiffness.h"
#include "Support/ShellMeshGenerator.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

using namespace faceplan;

namespace {

struct BoundaryScene {
  PrecomputeRequest request;
};

// Inner and outer surfaces prescribed (all of them movable), middle layers interior; the outer
// surface's first half is also listed as kept, which must return the prescribed values.
PrecomputeRequest BoundaryDriven(int subdivisions, int layers) {
  const ShellMesh shell = MakeSphericalShell(subdivisions, layers, 10.0, 16.0);
  PrecomputeRequest request;
  request.mesh = shell.mesh;
  request.materials = Materials::Uniform(2.0e3, 0.42);
  for (int id : shell.innerNodes)
    request.sets.constrained.push_back(id);
  for (int id : shell.outerNodes)
    request.sets.constrained.push_back(id);
  request.sets.movable = request.sets.constrained;
  // Kept: every node of the middle layer.
  for (int v = 0; v < shell.nodesPerLayer; ++v)
    request.sets.kept.push_back((layers / 2) * shell.nodesPerLayer + v);
  return request;
}

RowVectors3d FieldAt(const PrecomputeRequest& r, const std::vector<int>& nodes,
                     const Eigen::Matrix3d& A, const Eigen::Vector3d& b) {
  RowVectors3d u(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t k = 0; k < nodes.size(); ++k)
    u.row(k) = (A * r.mesh.points.row(nodes[k]).transpose() + b).transpose();
  return u;
}

void ExpectReproduces(SolveMethod method, const Eigen::Matrix3d& A, const Eigen::Vector3d& b) {
  PrecomputeRequest request = BoundaryDriven(4, 4);
  request.options.method = method;
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  SolveInput input;
  input.movableDisplacement = FieldAt(request, request.sets.movable, A, b);
  input.recoverInterior = true;
  SolveResult result;
  Status s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok) << s.message;
  std::vector<int> all(request.mesh.numPoints());
  for (size_t i = 0; i < all.size(); ++i)
    all[i] = static_cast<int>(i);
  const RowVectors3d exact = FieldAt(request, all, A, b);
  EXPECT_LT(RelativeMaxDifference(result.allDisplacement, exact), 1e-12);
  const double scale = exact.cwiseAbs().maxCoeff();
  const RowVectors3d exactKept = FieldAt(request, request.sets.kept, A, b);
  EXPECT_LT((result.keptDisplacement - exactKept).cwiseAbs().maxCoeff() / scale, 1e-12);
}

} // namespace

TEST(PatchTest, LinearFieldReproducedInsideCachedFactor) {
  Eigen::Matrix3d A;
  A << 0.01, -0.02, 0.005, 0.03, 0.002, -0.01, 0.004, 0.02, -0.015;
  ExpectReproduces(SolveMethod::CachedFactor, A, Eigen::Vector3d(0.1, -0.2, 0.3));
}

TEST(PatchTest, LinearFieldReproducedInsideDenseResponse) {
  Eigen::Matrix3d A;
  A << -0.02, 0.01, 0.0, 0.005, 0.03, 0.01, -0.01, 0.0, 0.02;
  ExpectReproduces(SolveMethod::DenseResponse, A, Eigen::Vector3d(-0.3, 0.1, 0.05));
}

TEST(RigidMotion, ZeroStrainAndZeroReaction) {
  PrecomputeRequest request = BoundaryDriven(4, 4);
  // Only the inner surface is held; the rest follows the rigid motion freely.
  const int perLayer = static_cast<int>(request.sets.kept.size());
  request.sets.constrained.resize(perLayer);
  request.sets.movable = request.sets.constrained;
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  // A small rotation (skew matrix) plus a translation.
  Eigen::Matrix3d W;
  W << 0, -0.02, 0.01, 0.02, 0, -0.03, -0.01, 0.03, 0;
  const Eigen::Vector3d t(0.5, -0.25, 1.0);
  SolveInput input;
  input.movableDisplacement = FieldAt(request, request.sets.movable, W, t);
  input.recoverInterior = true;
  SolveResult result;
  ASSERT_TRUE(Solve(*system, input, result).ok);
  const RowVectors3d& u = result.allDisplacement;
  double maxStrain = 0.0, maxForce = 0.0, forceScale = 0.0;
  Eigen::MatrixXd nodalForce = Eigen::MatrixXd::Zero(request.mesh.numPoints(), 3);
  TetCorners c;
  for (Eigen::Index e = 0; e < request.mesh.numTets(); ++e) {
    Eigen::Matrix<double, 12, 1> ue;
    for (int k = 0; k < 4; ++k) {
      c.row(k) = request.mesh.points.row(request.mesh.tets(e, k));
      ue.segment<3>(3 * k) = u.row(request.mesh.tets(e, k)).transpose();
    }
    // Displacement gradient from the linear interpolant; its symmetric part is the strain.
    Eigen::Matrix3d edges, du;
    for (int k = 0; k < 3; ++k) {
      edges.col(k) = (c.row(k + 1) - c.row(0)).transpose();
      du.col(k) = ue.segment<3>(3 * (k + 1)) - ue.segment<3>(0);
    }
    const Eigen::Matrix3d grad = du * edges.inverse();
    maxStrain = std::max(maxStrain, (0.5 * (grad + grad.transpose())).cwiseAbs().maxCoeff());
    const ElementMatrix ke = TetStiffness(c, 2.0e3, 0.42);
    const Eigen::Matrix<double, 12, 1> fe = ke * ue;
    forceScale = std::max(forceScale, (ke.cwiseAbs() * ue.cwiseAbs()).maxCoeff());
    for (int k = 0; k < 4; ++k)
      nodalForce.row(request.mesh.tets(e, k)) += fe.segment<3>(3 * k).transpose();
  }
  maxForce = nodalForce.cwiseAbs().maxCoeff();
  EXPECT_LT(maxStrain, 1e-12);
  EXPECT_LT(maxForce / forceScale, 1e-12); // reactions at the held nodes included
}
