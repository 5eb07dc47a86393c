// SPDX-License-Identifier: BSD-3-Clause
#include "Mesh/LipSeal.h"

#include "Mesh/MeshValidation.h"
#include "Mesh/TetGeometry.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace faceplan {

namespace {

struct BoundaryFace {
  std::array<int, 3> nodes; // ordered so that the normal points out of the tissue
  Eigen::Index cell;        // the tissue cell behind the face
};

// Faces used by one cell only, outward. A positively oriented cell (x3 on the side of
// (x1 - x0) x (x2 - x0)) has these outward faces.
std::vector<BoundaryFace> BoundaryFaces(const TetMesh& mesh) {
  static const int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, std::pair<int, BoundaryFace>> faces;
  for (Eigen::Index c = 0; c < mesh.numTets(); ++c)
    for (const auto& f : kFaces) {
      BoundaryFace face{{mesh.tets(c, f[0]), mesh.tets(c, f[1]), mesh.tets(c, f[2])}, c};
      std::array<int, 3> key = face.nodes;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, 0, face);
      ++it->second.first;
    }
  std::vector<BoundaryFace> out;
  for (const auto& [key, entry] : faces)
    if (entry.first == 1)
      out.push_back(entry.second);
  return out;
}

// The mean-ratio quality (TetMeanRatio) of a positively oriented cell; 0 for any other.
double OrientedMeanRatio(const Eigen::Vector3d x[4]) {
  TetCorners corners;
  for (int i = 0; i < 4; ++i)
    corners.row(i) = x[i].transpose();
  return TetVolume(corners) > 0.0 ? TetMeanRatio(corners) : 0.0;
}

struct CellKeyHash {
  size_t operator()(const std::array<long long, 3>& k) const {
    return static_cast<size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
  }
};

} // namespace

Status AddLipSeal(const TetMesh& mesh, const Materials& materials, const LipSealOptions& options,
                  TetMesh& sealed, Materials& sealedMaterials, LipSealInfo& info) {
  info = LipSealInfo{};
  if (!std::isfinite(options.gap) || options.gap < 0.0)
    return Status::Error("LipSeal: the gap must be a finite distance >= 0 (got " +
                         std::to_string(options.gap) + ")");
  if (!std::isfinite(options.stiffnessFactor) || options.stiffnessFactor <= 0.0)
    return Status::Error("LipSeal: the bridges' stiffness factor must be finite and > 0");
  const Eigen::Index m = mesh.numTets();
  auto perCell = [m](const Eigen::VectorXd& v) {
    return v.size() == 1 ? Eigen::VectorXd(Eigen::VectorXd::Constant(m, v[0])) : v;
  };
  if ((materials.youngsModulus.size() != 1 && materials.youngsModulus.size() != m) ||
      (materials.poissonRatio.size() != 1 && materials.poissonRatio.size() != m) ||
      (materials.density.size() > 1 && materials.density.size() != m))
    return Status::Error("LipSeal: the materials have neither one entry nor one per cell");

  const std::vector<BoundaryFace> faces =
      options.gap > 0.0 ? BoundaryFaces(mesh) : std::vector<BoundaryFace>{};
  // Outward normals of the boundary nodes (area-weighted) and a grid of them with gap-sized cells.
  std::vector<Eigen::Vector3d> normal(mesh.numPoints(), Eigen::Vector3d::Zero());
  std::vector<char> onBoundary(mesh.numPoints(), 0);
  for (const BoundaryFace& f : faces) {
    const Eigen::Vector3d a = mesh.points.row(f.nodes[0]), b = mesh.points.row(f.nodes[1]),
                          c = mesh.points.row(f.nodes[2]);
    const Eigen::Vector3d area = (b - a).cross(c - a);
    for (int k : f.nodes) {
      normal[k] += area;
      onBoundary[k] = 1;
    }
  }
  std::unordered_map<std::array<long long, 3>, std::vector<int>, CellKeyHash> grid;
  auto key = [&](const Eigen::Vector3d& x) {
    return std::array<long long, 3>{static_cast<long long>(std::floor(x[0] / options.gap)),
                                    static_cast<long long>(std::floor(x[1] / options.gap)),
                                    static_cast<long long>(std::floor(x[2] / options.gap))};
  };
  for (Eigen::Index i = 0; i < mesh.numPoints(); ++i)
    if (onBoundary[i]) {
      normal[i].normalize();
      grid[key(mesh.points.row(i))].push_back(static_cast<int>(i));
    }

  std::vector<std::array<int, 4>> bridges;
  std::vector<Eigen::Index> behind;
  std::set<std::array<int, 4>> seen;
  std::set<int> tied;
  for (const BoundaryFace& f : faces) {
    Eigen::Vector3d x[4] = {mesh.points.row(f.nodes[0]), mesh.points.row(f.nodes[1]),
                            mesh.points.row(f.nodes[2]), Eigen::Vector3d::Zero()};
    const Eigen::Vector3d centroid = (x[0] + x[1] + x[2]) / 3.0;
    Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]);
    if (!(n.norm() > 0.0))
      continue;
    n.normalize();
    const auto k = key(centroid);
    int best = -1;
    double bestDistance = options.gap;
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end())
            continue;
          for (int node : it->second) {
            if (node == f.nodes[0] || node == f.nodes[1] || node == f.nodes[2])
              continue;
            const Eigen::Vector3d d = mesh.points.row(node).transpose() - centroid;
            const double distance = d.norm();
            if (!(distance > 0.0) || distance > bestDistance ||
                d.dot(n) < options.facingCosine * distance ||
                normal[node].dot(n) > -options.opposedCosine)
              continue;
            x[3] = mesh.points.row(node);
            if (OrientedMeanRatio(x) < options.minimumQuality)
              continue;
            best = node;
            bestDistance = distance;
          }
        }
    if (best < 0)
      continue;
    std::array<int, 4> cell{f.nodes[0], f.nodes[1], f.nodes[2], best};
    std::array<int, 4> sorted = cell;
    std::sort(sorted.begin(), sorted.end());
    if (!seen.insert(sorted).second)
      continue;
    bridges.push_back(cell);
    behind.push_back(f.cell);
    tied.insert(best);
    for (int node : f.nodes)
      tied.insert(node);
  }

  sealed.points = mesh.points;
  sealed.tets.resize(m + static_cast<Eigen::Index>(bridges.size()), 4);
  sealed.tets.topRows(m) = mesh.tets;
  const Eigen::VectorXd E = perCell(materials.youngsModulus), nu = perCell(materials.poissonRatio);
  const Eigen::VectorXd rho =
      materials.density.size() == 0 ? Eigen::VectorXd::Zero(m) : perCell(materials.density);
  sealedMaterials.youngsModulus.resize(sealed.numTets());
  sealedMaterials.poissonRatio.resize(sealed.numTets());
  sealedMaterials.density = Eigen::VectorXd::Zero(sealed.numTets());
  sealedMaterials.youngsModulus.head(m) = E;
  sealedMaterials.poissonRatio.head(m) = nu;
  sealedMaterials.density.head(m) = rho;
  // The bridges are a weld, not tissue: small-strain elastic under the large-deformation model
  // too, so their tangent does not change as the lips move and shear them (a stiff neo-Hookean
  // bridge's does, by its stiffness times the rotation, which the precomputed factor misses).
  sealedMaterials.smallStrain.assign(static_cast<size_t>(sealed.numTets()), 0);
  if (materials.smallStrain.size() == static_cast<size_t>(m))
    std::copy(materials.smallStrain.begin(), materials.smallStrain.end(),
              sealedMaterials.smallStrain.begin());
  std::fill(sealedMaterials.smallStrain.begin() + m, sealedMaterials.smallStrain.end(), 1);
  for (size_t b = 0; b < bridges.size(); ++b) {
    const Eigen::Index c = m + static_cast<Eigen::Index>(b);
    for (int j = 0; j < 4; ++j)
      sealed.tets(c, j) = bridges[b][j];
    sealedMaterials.youngsModulus[c] = options.stiffnessFactor * E[behind[b]];
    sealedMaterials.poissonRatio[c] = nu[behind[b]];
  }
  info.bridges = static_cast<long long>(bridges.size());
  info.tiedNodes = static_cast<long long>(tied.size());
  return Status::Ok();
}

} // namespace faceplan
