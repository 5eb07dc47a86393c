// SPDX-License-Identifier: BSD-3-Clause
#include "Support/FEMTestScenes.h"

#include "Support/BoxMeshGenerator.h"

namespace faceplan::testing {

PrecomputeRequest ShellRequest(int subdivisions, int layers, double E, double nu) {
  FaceLikeScene scene = MakeFaceLikeScene(subdivisions, layers, 0.1);
  PrecomputeRequest request;
  request.mesh = scene.shell.mesh;
  request.materials = Materials::Uniform(E, nu, 1.0e-6);
  request.sets.constrained = scene.constrained;
  request.sets.movable = scene.movable;
  request.sets.kept = scene.kept;
  return request;
}

RowVectors3d SmoothRoiField(const PrecomputeRequest& request, double amplitude) {
  RowVectors3d u(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  for (size_t k = 0; k < request.sets.movable.size(); ++k) {
    const Eigen::RowVector3d p = request.mesh.points.row(request.sets.movable[k]);
    u.row(k) << amplitude * std::sin(p(0) / 20.0), amplitude * std::cos(p(1) / 25.0) * 0.5,
        -amplitude * (1.0 + std::sin(p(0) * p(1) / 900.0));
  }
  return u;
}

SolveInput PlateMove(const PrecomputeRequest& request, double press) {
  SolveInput input;
  input.movableDisplacement =
      RowVectors3d::Zero(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  input.movableDisplacement.col(2).setConstant(-press);
  input.recoverInterior = true;
  return input;
}

PrecomputeRequest PressedBlockRequest(double lx, double ly, double lz, double nu, double E) {
  PrecomputeRequest r;
  const int nx = 5, ny = 4, nz = 3;
  r.mesh = MakeBoxTetMesh(nx, ny, nz, lx, ly, lz);
  r.materials = Materials::Uniform(E, nu);
  for (Eigen::Index i = 0; i < r.mesh.numPoints(); ++i) {
    const Eigen::RowVector3d p = r.mesh.points.row(i);
    const int node = static_cast<int>(i);
    r.sets.kept.push_back(node);
    if (p.norm() == 0.0) {
      r.sets.constrained.push_back(node); // tied
    } else if (p.z() == 0.0 || p.z() == lz) {
      r.sets.constrained.push_back(node);
      r.sets.sliding.push_back(node);
      r.sets.slidingNormal.push_back(Eigen::Vector3d::UnitZ());
      if (p.z() == lz)
        r.sets.movable.push_back(node);
    } else if (p.y() == 0.0 && p.x() == lx) {
      r.sets.constrained.push_back(node);
      r.sets.sliding.push_back(node);
      r.sets.slidingNormal.push_back(Eigen::Vector3d::UnitY());
    }
  }
  return r;
}

PrecomputeRequest SlidingShellRequest(double push, RowVectors3d& moves) {
  const ShellMesh shell = MakeSphericalShell(4, 2, 40.0, 55.0);
  PrecomputeRequest r;
  r.mesh = shell.mesh;
  r.materials = Materials::Uniform(3000.0, 0.45);
  std::vector<Eigen::RowVector3d> pushes;
  for (int node : shell.innerNodes) {
    const Eigen::Vector3d x = r.mesh.points.row(node).transpose();
    const Eigen::Vector3d n = x.normalized();
    r.sets.constrained.push_back(node);
    r.sets.kept.push_back(node);
    if (n.z() < -0.6)
      continue; // tied
    r.sets.sliding.push_back(node);
    r.sets.slidingNormal.push_back(n);
    if (n.z() > 0.7) {
      r.sets.movable.push_back(node);
      const double q = (1.0 - n.z()) / 0.3;
      pushes.push_back((push * (1.0 - q * q) * n + Eigen::Vector3d(0.4, -0.2, 0.0)).transpose());
    }
  }
  for (int node : shell.outerNodes)
    r.sets.kept.push_back(node);
  moves.resize(static_cast<Eigen::Index>(pushes.size()), 3);
  for (size_t k = 0; k < pushes.size(); ++k)
    moves.row(static_cast<Eigen::Index>(k)) = pushes[k];
  return r;
}

} // namespace faceplan::testing
