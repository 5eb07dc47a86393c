// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Small surface meshes for the ROI / Bezier-cut tests (generated, no files).
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

namespace faceplan::testmesh {

// Unit icosphere (outward triangles), `levels` subdivisions of an icosahedron.
inline SurfaceMesh Icosphere(int levels, double radius = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v)
    p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end())
        return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = g;
  }
  SurfaceMesh m;
  m.points.resize(Eigen::Index(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    m.points.row(Eigen::Index(i)) = radius * v[i].transpose();
  for (auto& tri : f)
    m.addCell({tri[0], tri[1], tri[2]});
  return m;
}

// Regular grid of triangles over [x0,x1] x [y0,y1] at z = 0 (normals +z).
inline SurfaceMesh PlaneGrid(int nx, int ny, double x0 = 0, double x1 = 1, double y0 = 0,
                             double y1 = 1) {
  SurfaceMesh m;
  m.points.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.points.row(j * (nx + 1) + i) << x0 + (x1 - x0) * i / nx, y0 + (y1 - y0) * j / ny, 0.0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const std::int64_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      m.addCell({a, b, c});
      m.addCell({a, c, d});
    }
  return m;
}

// Closed axis-aligned box [lo, hi] with outward triangles, about `h` apart.
inline SurfaceMesh Box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double h) {
  SurfaceMesh m;
  std::map<std::tuple<long, long, long>, std::int64_t> ids;
  std::vector<Eigen::Vector3d> pts;
  auto id = [&](const Eigen::Vector3d& p) {
    auto key = std::make_tuple(std::lround(p.x() * 1e6), std::lround(p.y() * 1e6),
                               std::lround(p.z() * 1e6));
    auto it = ids.find(key);
    if (it != ids.end())
      return it->second;
    pts.push_back(p);
    return ids[key] = std::int64_t(pts.size()) - 1;
  };
  const Eigen::Vector3d d = hi - lo;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3; // e_a x e_b = e_axis
      const int na = std::max(1, int(std::lround(d[a] / h))),
                nb = std::max(1, int(std::lround(d[b] / h)));
      auto P = [&](int i, int j) {
        Eigen::Vector3d p;
        p[axis] = side ? hi[axis] : lo[axis];
        p[a] = lo[a] + d[a] * i / na;
        p[b] = lo[b] + d[b] * j / nb;
        return id(p);
      };
      for (int j = 0; j < nb; ++j)
        for (int i = 0; i < na; ++i) {
          std::int64_t p00 = P(i, j), p10 = P(i + 1, j), p11 = P(i + 1, j + 1), p01 = P(i, j + 1);
          if (side) {
            m.addCell({p00, p10, p11});
            m.addCell({p00, p11, p01});
          } else {
            m.addCell({p00, p11, p10});
            m.addCell({p00, p01, p11});
          }
        }
    }
  m.points.resize(Eigen::Index(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i)
    m.points.row(Eigen::Index(i)) = pts[i].transpose();
  return m;
}

} // namespace faceplan::testmesh
