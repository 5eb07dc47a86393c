// SPDX-License-Identifier: BSD-3-Clause
#include "Element/QuadraticTet.h"

#include "Common/ParallelFor.h"
#include "Element/ElementStiffness.h"

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <mutex>

namespace faceplan {

// Gradients (w.r.t. reference coordinates xi = (L1, L2, L3)) of the 10 shape functions at the
// barycentric point L.
Eigen::Matrix<double, 10, 3> Tet10ReferenceGradients(const Eigen::Vector4d& L) {
  Eigen::Matrix<double, 4, 3> dL;
  dL << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Eigen::Matrix<double, 10, 3> g;
  for (int i = 0; i < 4; ++i)
    g.row(i) = (4.0 * L[i] - 1.0) * dL.row(i);
  for (int e = 0; e < 6; ++e) {
    const int i = kTet10EdgeCorners[e][0], j = kTet10EdgeCorners[e][1];
    g.row(4 + e) = 4.0 * (L[i] * dL.row(j) + L[j] * dL.row(i));
  }
  return g;
}

namespace {

Eigen::Matrix<double, 10, 1> ShapeValues(const Eigen::Vector4d& L) {
  Eigen::Matrix<double, 10, 1> n;
  for (int i = 0; i < 4; ++i)
    n[i] = L[i] * (2.0 * L[i] - 1.0);
  for (int e = 0; e < 6; ++e)
    n[4 + e] = 4.0 * L[kTet10EdgeCorners[e][0]] * L[kTet10EdgeCorners[e][1]];
  return n;
}

// Degree-2 four-point rule on the reference tetrahedron (volume 1/6).
struct Rule {
  Eigen::Vector4d L[4];
  double weight = 1.0 / 24.0;
  Rule() {
    const double a = 0.5854101966249685, b = 0.1381966011250105;
    for (int q = 0; q < 4; ++q) {
      L[q] = Eigen::Vector4d::Constant(b);
      L[q][q] = a;
    }
  }
};
const Rule& QuadratureRule() {
  static const Rule rule;
  return rule;
}

} // namespace

Status MakeQuadraticMesh(const TetMesh& mesh, QuadraticMesh& out,
                         const MidEdgeProjection& projection) {
  const Eigen::Index n = mesh.numPoints(), m = mesh.numTets();
  out = QuadraticMesh{};
  out.numCorners = n;
  out.cells.resize(m, 10);

  // Edges: sort (key, cell * 6 + local) pairs so numbering is deterministic.
  std::vector<std::pair<std::uint64_t, std::int64_t>> keys(static_cast<size_t>(m) * 6);
  for (Eigen::Index c = 0; c < m; ++c)
    for (int e = 0; e < 6; ++e) {
      std::uint64_t a = static_cast<std::uint32_t>(mesh.tets(c, kTet10EdgeCorners[e][0]));
      std::uint64_t b = static_cast<std::uint32_t>(mesh.tets(c, kTet10EdgeCorners[e][1]));
      if (a > b)
        std::swap(a, b);
      keys[c * 6 + e] = {(a << 32) | b, c * 6 + e};
    }
  std::sort(keys.begin(), keys.end());
  for (size_t k = 0; k < keys.size(); ++k) {
    if (k == 0 || keys[k].first != keys[k - 1].first)
      out.edges.push_back(
          {static_cast<int>(keys[k].first >> 32), static_cast<int>(keys[k].first & 0xffffffffu)});
    const std::int64_t slot = keys[k].second;
    out.cells(slot / 6, 4 + slot % 6) = static_cast<int>(n + out.edges.size() - 1);
  }
  for (Eigen::Index c = 0; c < m; ++c)
    for (int k = 0; k < 4; ++k)
      out.cells(c, k) = mesh.tets(c, k);
  if (n + static_cast<Eigen::Index>(out.edges.size()) > std::numeric_limits<int>::max())
    return Status::Error("mesh too large for a quadratic mesh with 32-bit ids");

  // Boundary faces appear in one cell only; their edges are boundary edges.
  out.boundaryEdge.assign(out.edges.size(), 0);
  struct Face {
    std::array<int, 3> sorted;
    std::int64_t cell;
    int local; // the opposite corner
    bool operator<(const Face& o) const { return sorted < o.sorted; }
  };
  std::vector<Face> faces(static_cast<size_t>(m) * 4);
  for (Eigen::Index c = 0; c < m; ++c)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f;
      for (int j = 0, t = 0; j < 4; ++j)
        if (j != k)
          f[t++] = mesh.tets(c, j);
      std::sort(f.begin(), f.end());
      faces[c * 4 + k] = {f, c, k};
    }
  std::sort(faces.begin(), faces.end());
  for (size_t k = 0; k < faces.size();) {
    size_t j = k + 1;
    while (j < faces.size() && faces[j].sorted == faces[k].sorted)
      ++j;
    if (j - k == 1) {
      const Face& f = faces[k];
      for (int e = 0; e < 6; ++e)
        if (kTet10EdgeCorners[e][0] != f.local && kTet10EdgeCorners[e][1] != f.local)
          out.boundaryEdge[out.cells(f.cell, 4 + e) - n] = 1;
    }
    k = j;
  }

  out.points.resize(n + static_cast<Eigen::Index>(out.edges.size()), 3);
  out.points.topRows(n) = mesh.points;
  for (size_t e = 0; e < out.edges.size(); ++e) {
    const int a = out.edges[e][0], b = out.edges[e][1];
    Eigen::Vector3d mid = 0.5 * (mesh.points.row(a) + mesh.points.row(b)).transpose();
    if (projection && out.boundaryEdge[e])
      mid = projection(mid, a, b);
    out.points.row(n + static_cast<Eigen::Index>(e)) = mid.transpose();
  }
  return Status::Ok();
}

Tet10Matrix Tet10Stiffness(const Tet10Nodes& x, double E, double nu, double* minJacobian,
                           bool meanDilatation) {
  double lambda, mu;
  LameParameters(E, nu, lambda, mu);
  const double pointLambda = meanDilatation ? 0.0 : lambda;
  const Rule& rule = QuadratureRule();
  Tet10Matrix ke = Tet10Matrix::Zero();
  Eigen::Matrix<double, 30, 1> divergence = Eigen::Matrix<double, 30, 1>::Zero(); // int div N
  double volume = 0.0;
  double smallest = std::numeric_limits<double>::infinity();
  for (int q = 0; q < 4; ++q) {
    const Eigen::Matrix<double, 10, 3> gref = Tet10ReferenceGradients(rule.L[q]);
    const Eigen::Matrix3d J = x.transpose() * gref; // J(i, j) = d x_i / d xi_j
    const double det = J.determinant();
    smallest = std::min(smallest, det);
    const Eigen::Matrix<double, 10, 3> g = gref * J.inverse(); // rows: grad_x N_a
    const double w = rule.weight * det;
    volume += w;
    for (int a = 0; a < 10; ++a)
      divergence.segment<3>(3 * a) += w * g.row(a).transpose();
    for (int a = 0; a < 10; ++a)
      for (int b = a; b < 10; ++b) {
        const Eigen::RowVector3d ga = g.row(a), gb = g.row(b);
        Eigen::Matrix3d block = pointLambda * ga.transpose() * gb + mu * gb.transpose() * ga;
        block.diagonal().array() += mu * ga.dot(gb);
        ke.block<3, 3>(3 * a, 3 * b) += w * block;
      }
  }
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b < a; ++b)
      ke.block<3, 3>(3 * a, 3 * b) = ke.block<3, 3>(3 * b, 3 * a).transpose();
  if (meanDilatation && volume > 0.0)
    ke += (lambda / volume) * divergence * divergence.transpose();
  if (minJacobian)
    *minJacobian = smallest;
  return ke;
}

Eigen::Matrix<double, 10, 1> Tet10ShapeIntegrals(const Tet10Nodes& x) {
  const Rule& rule = QuadratureRule();
  Eigen::Matrix<double, 10, 1> sum = Eigen::Matrix<double, 10, 1>::Zero();
  for (int q = 0; q < 4; ++q) {
    const Eigen::Matrix3d J = x.transpose() * Tet10ReferenceGradients(rule.L[q]);
    sum += rule.weight * J.determinant() * ShapeValues(rule.L[q]);
  }
  return sum;
}

void ComputePackedTet10Stiffness(const QuadraticMesh& mesh, const Materials& materials,
                                 PackedElementMatrices& packed,
                                 std::vector<long long>& invalidCells, bool meanDilatation) {
  const Eigen::Index m = mesh.cells.rows();
  packed.resize(static_cast<size_t>(m) * kPackedTet10Size);
  invalidCells.clear();
  std::mutex invalidMutex;
  ParallelFor(m, 4000, [&](std::int64_t begin, std::int64_t end) {
    Tet10Nodes nodes;
    std::vector<long long> bad;
    for (std::int64_t e = begin; e < end; ++e) {
      for (int k = 0; k < 10; ++k)
        nodes.row(k) = mesh.points.row(mesh.cells(e, k));
      double minJ = 0.0;
      const Tet10Matrix ke =
          Tet10Stiffness(nodes, materials.E(e), materials.nu(e), &minJ, meanDilatation);
      if (!(minJ > 0.0))
        bad.push_back(e);
      double* out = packed.data() + static_cast<size_t>(e) * kPackedTet10Size;
      for (int p = 0; p < 30; ++p)
        for (int q = p; q < 30; ++q)
          *out++ = ke(p, q);
    }
    std::lock_guard<std::mutex> lock(invalidMutex);
    invalidCells.insert(invalidCells.end(), bad.begin(), bad.end());
  });
  std::sort(invalidCells.begin(), invalidCells.end());
}

} // namespace faceplan
