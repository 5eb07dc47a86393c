// SPDX-License-Identifier: BSD-3-Clause
#include "Support/BoxMeshGenerator.h"

#include <Eigen/Geometry>
#include <array>

namespace faceplan {

TetMesh MakeBoxTetMesh(int nx, int ny, int nz, double lx, double ly, double lz) {
  TetMesh mesh;
  auto id = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  mesh.points.resize(Eigen::Index(nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        mesh.points.row(id(i, j, k)) << lx * i / nx, ly * j / ny, lz * k / nz;
  // The 6 paths from corner 0 to corner 7 of the unit cube, one axis step at a time.
  const std::array<std::array<int, 3>, 6> orders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  mesh.tets.resize(Eigen::Index(6) * nx * ny * nz, 4);
  Eigen::Index t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& order : orders) {
          std::array<int, 3> at = {i, j, k};
          int corners[4];
          corners[0] = id(at[0], at[1], at[2]);
          for (int step = 0; step < 3; ++step) {
            ++at[order[step]];
            corners[step + 1] = id(at[0], at[1], at[2]);
          }
          mesh.tets.row(t) << corners[0], corners[1], corners[2], corners[3];
          // Orient positively (odd permutations of the axes give negative volume).
          const Eigen::Vector3d a = mesh.points.row(corners[1]) - mesh.points.row(corners[0]);
          const Eigen::Vector3d b = mesh.points.row(corners[2]) - mesh.points.row(corners[0]);
          const Eigen::Vector3d c = mesh.points.row(corners[3]) - mesh.points.row(corners[0]);
          if (a.dot(b.cross(c)) < 0)
            std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
          ++t;
        }
  return mesh;
}

} // namespace faceplan
