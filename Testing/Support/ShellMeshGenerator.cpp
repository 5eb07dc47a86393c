// SPDX-License-Identifier: BSD-3-Clause
#include "Support/ShellMeshGenerator.h"

#include "Element/ElementStiffness.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

namespace faceplan {

namespace {

struct SphereTriangulation {
  std::vector<Eigen::Vector3d> vertices; // unit length
  std::vector<std::array<int, 3>> triangles;
};

// Icosahedron with every edge cut into `s` pieces, vertices pushed onto the unit sphere.
// Shared vertices are found by an exact key: each point is (i*A + j*B + k*C)/s for an icosahedron
// face (A,B,C), so the sorted (vertex, weight) pairs identify it whichever face produced it.
SphereTriangulation Icosphere(int s) {
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> ico = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                                      {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                                      {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  SphereTriangulation out;
  std::map<std::array<int, 6>, int> index;
  auto vertexId = [&](int a, int wa, int b, int wb, int c, int wc) {
    std::array<std::pair<int, int>, 3> terms = {{{a, wa}, {b, wb}, {c, wc}}};
    for (auto& t : terms)
      if (t.second == 0)
        t.first = -1;
    std::sort(terms.begin(), terms.end());
    const std::array<int, 6> key = {terms[0].first,  terms[0].second, terms[1].first,
                                    terms[1].second, terms[2].first,  terms[2].second};
    auto it = index.find(key);
    if (it != index.end())
      return it->second;
    const Eigen::Vector3d p = (wa * ico[a] + wb * ico[b] + wc * ico[c]) / double(s);
    out.vertices.push_back(p.normalized());
    const int id = static_cast<int>(out.vertices.size()) - 1;
    index.emplace(key, id);
    return id;
  };
  for (const auto& f : faces) {
    // Grid point (i, j) has weights (s-i-j, i, j) on corners (A, B, C).
    auto at = [&](int i, int j) { return vertexId(f[0], s - i - j, f[1], i, f[2], j); };
    for (int i = 0; i < s; ++i) {
      for (int j = 0; i + j < s; ++j) {
        out.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j + 1 < s)
          out.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  return out;
}

// Three tetrahedra of a prism (v0..v2 bottom, v3..v5 above them). Each quad face is cut along the
// diagonal through its smallest global index, so neighbouring prisms agree on shared faces.
void SplitPrism(const std::array<int, 6>& v, std::vector<std::array<int, 4>>& tets) {
  static const int rotation[6][6] = {{0, 1, 2, 3, 4, 5}, {1, 2, 0, 4, 5, 3}, {2, 0, 1, 5, 3, 4},
                                     {3, 5, 4, 0, 2, 1}, {4, 3, 5, 1, 0, 2}, {5, 4, 3, 2, 1, 0}};
  const int first = static_cast<int>(std::min_element(v.begin(), v.end()) - v.begin());
  std::array<int, 6> r;
  for (int k = 0; k < 6; ++k)
    r[k] = v[rotation[first][k]];
  if (std::min(r[1], r[5]) < std::min(r[2], r[4])) {
    tets.push_back({r[0], r[1], r[2], r[5]});
    tets.push_back({r[0], r[1], r[5], r[4]});
  } else {
    tets.push_back({r[0], r[1], r[2], r[4]});
    tets.push_back({r[0], r[4], r[2], r[5]});
  }
  tets.push_back({r[0], r[4], r[5], r[3]});
}

} // namespace

ShellMesh MakeSphericalShell(int subdivisions, int layers, double innerRadius, double outerRadius) {
  const SphereTriangulation sphere = Icosphere(std::max(1, subdivisions));
  layers = std::max(1, layers);
  const int perLayer = static_cast<int>(sphere.vertices.size());
  ShellMesh shell;
  shell.nodesPerLayer = perLayer;
  shell.mesh.points.resize(static_cast<Eigen::Index>(perLayer) * (layers + 1), 3);
  for (int l = 0; l <= layers; ++l) {
    const double r = innerRadius + (outerRadius - innerRadius) * l / layers;
    for (int v = 0; v < perLayer; ++v)
      shell.mesh.points.row(l * perLayer + v) = r * sphere.vertices[v].transpose();
  }
  std::vector<std::array<int, 4>> tets;
  tets.reserve(3 * sphere.triangles.size() * layers);
  for (int l = 0; l < layers; ++l) {
    for (const auto& t : sphere.triangles) {
      SplitPrism({l * perLayer + t[0], l * perLayer + t[1], l * perLayer + t[2],
                  (l + 1) * perLayer + t[0], (l + 1) * perLayer + t[1], (l + 1) * perLayer + t[2]},
                 tets);
    }
  }
  shell.mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  TetCorners corners;
  for (size_t e = 0; e < tets.size(); ++e) {
    auto tet = tets[e];
    for (int k = 0; k < 4; ++k)
      corners.row(k) = shell.mesh.points.row(tet[k]);
    if (TetVolume(corners) < 0)
      std::swap(tet[2], tet[3]);
    for (int k = 0; k < 4; ++k)
      shell.mesh.tets(e, k) = tet[k];
  }
  for (int v = 0; v < perLayer; ++v) {
    shell.innerNodes.push_back(v);
    shell.outerNodes.push_back(layers * perLayer + v);
  }
  return shell;
}

FaceLikeScene MakeFaceLikeScene(int subdivisions, int layers, double roiFraction) {
  // Millimetres: a skull-sized sphere under 15 mm of soft tissue.
  const double inner = 80.0, outer = 95.0;
  FaceLikeScene scene;
  scene.shell = MakeSphericalShell(subdivisions, layers, inner, outer);
  // A polar cap holds the fraction (1 - cos theta) / 2 of the sphere's area.
  const double capZ = inner * (1.0 - 2.0 * roiFraction);
  for (int node : scene.shell.innerNodes) {
    scene.constrained.push_back(node);
    if (scene.shell.mesh.points(node, 2) > capZ)
      scene.movable.push_back(node);
  }
  scene.kept = scene.shell.outerNodes;
  return scene;
}

} // namespace faceplan
