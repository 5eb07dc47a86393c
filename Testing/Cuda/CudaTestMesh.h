// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A small perturbed box mesh (Kuhn split: 6 tetrahedra per hexahedron, conforming), positively
// oriented, for backend agreement tests independent of the shell generator.
#include "Mesh/TetMesh.h"

#include <Eigen/Dense>
#include <random>
#include <utility>

namespace faceplan::testing {

inline TetMesh MakePerturbedBox(int nx, int ny, int nz, unsigned seed, double jitter = 0.1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  TetMesh mesh;
  const int px = nx + 1, py = ny + 1, pz = nz + 1;
  mesh.points.resize(static_cast<Eigen::Index>(px) * py * pz, 3);
  auto id = [&](int i, int j, int k) { return i + px * (j + py * k); };
  for (int k = 0; k < pz; ++k)
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i) {
        const bool interior = i > 0 && i < nx && j > 0 && j < ny && k > 0 && k < nz;
        const double d = interior ? 1.0 : 0.0;
        mesh.points.row(id(i, j, k)) << i + d * u(rng), 1.3 * j + d * u(rng), 0.7 * k + d * u(rng);
      }
  // Kuhn triangulation: the 6 paths from corner 0 to corner 7 through the cube's vertices.
  static const int paths[6][3] = {{1, 3, 7}, {1, 5, 7}, {2, 3, 7}, {2, 6, 7}, {4, 5, 7}, {4, 6, 7}};
  mesh.tets.resize(6 * nx * ny * nz, 4);
  Eigen::Index t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        auto corner = [&](int c) {
          return id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        };
        for (const auto& p : paths) {
          int v[4] = {corner(0), corner(p[0]), corner(p[1]), corner(p[2])};
          Eigen::Matrix3d edges;
          for (int c = 0; c < 3; ++c)
            edges.col(c) = (mesh.points.row(v[c + 1]) - mesh.points.row(v[0])).transpose();
          if (edges.determinant() < 0)
            std::swap(v[2], v[3]);
          mesh.tets.row(t++) << v[0], v[1], v[2], v[3];
        }
      }
  return mesh;
}

} // namespace faceplan::testing
