// SPDX-License-Identifier: BSD-3-Clause
#include "Element/NodalPressure.h"

#include "Element/QuadraticTet.h"

#include "Common/ParallelFor.h"
#include "Element/ElementStiffness.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace faceplan {

namespace {

double Lambda(const Materials& materials, Eigen::Index cell) {
  double lambda, mu;
  LameParameters(materials.E(cell), materials.nu(cell), lambda, mu);
  return lambda;
}

// Per cell: D(k, 3 a + c) = int phi_k dN_a/dx_c (k: corner, a: node) and P(k) = int phi_k, with the
// degree-2 four-point rule (exact for straight cells: phi_k is linear, dN_a/dx too).
bool CellPressureCoupling(const RowVectors3d& points, const int* cell,
                          Eigen::Matrix<double, 4, 30>& D, Eigen::Vector4d& P) {
  const double alpha = 0.5854101966249685, beta = 0.1381966011250105;
  D.setZero();
  P.setZero();
  Eigen::Matrix<double, 10, 3> x;
  for (int a = 0; a < 10; ++a)
    x.row(a) = points.row(cell[a]);
  for (int q = 0; q < 4; ++q) {
    Eigen::Vector4d L = Eigen::Vector4d::Constant(beta);
    L[q] = alpha;
    const Eigen::Matrix<double, 10, 3> gref = Tet10ReferenceGradients(L);
    const Eigen::Matrix3d J = x.transpose() * gref;
    const double det = J.determinant();
    if (!(det > 0.0))
      return false;
    const Eigen::Matrix<double, 10, 3> g = gref * J.inverse();
    const double w = det / 24.0;
    for (int k = 0; k < 4; ++k) {
      P[k] += w * L[k];
      for (int a = 0; a < 10; ++a)
        D.block<1, 3>(k, 3 * a) += (w * L[k]) * g.row(a);
    }
  }
  return true;
}

bool BuildCoupling(const RowVectors3d& points, const int* cells, Eigen::Index numCells,
                   const Materials& materials, const std::vector<int>& dofNode,
                   std::vector<Eigen::Triplet<double, int>>& triplets, Eigen::VectorXd& mass) {
  constexpr int Nodes = 10;
  triplets.reserve(static_cast<size_t>(numCells) * 4 * 3 * Nodes);
  Eigen::Matrix<double, 4, 3 * Nodes> D;
  Eigen::Vector4d P;
  for (Eigen::Index e = 0; e < numCells; ++e) {
    const double lambda = Lambda(materials, e);
    if (!(lambda > 0.0))
      continue; // keeps its own volumetric term (see ShearOnlyMaterials)
    const int* cell = cells + e * Nodes;
    if (!CellPressureCoupling(points, cell, D, P))
      return false;
    for (int k = 0; k < 4; ++k) {
      mass[cell[k]] += P[k] / lambda;
      for (int a = 0; a < Nodes; ++a) {
        const int node = dofNode[cell[a]];
        if (node < 0)
          continue;
        for (int c = 0; c < 3; ++c)
          triplets.emplace_back(cell[k], 3 * node + c, D(k, 3 * a + c));
      }
    }
  }
  return true;
}

} // namespace

Materials ShearOnlyMaterials(const Materials& materials) {
  const Eigen::Index m = std::max(materials.youngsModulus.size(), materials.poissonRatio.size());
  Materials out;
  out.density = materials.density;
  out.youngsModulus.resize(m);
  out.poissonRatio.resize(m);
  for (Eigen::Index e = 0; e < m; ++e) {
    const double E = materials.E(e), nu = materials.nu(e);
    const bool split = Lambda(materials, e) > 0.0;
    out.youngsModulus[e] = split ? E / (1.0 + nu) : E;
    out.poissonRatio[e] = split ? 0.0 : nu;
  }
  return out;
}

Status NodalPressureStiffness(const RowVectors3d& points, const int* cells, Eigen::Index numCells,
                              int nodesPerCell, const Materials& materials,
                              const std::vector<int>& dofNode, int numDofNodes,
                              SparseMatrix& upper) {
  const Eigen::Index pressureNodes = points.rows();
  std::vector<Eigen::Triplet<double, int>> triplets;
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(pressureNodes); // sum of int phi_n / lambda
  if (nodesPerCell != 10)
    return Status::Error("nodal pressure: 10-node cells only");
  if (!BuildCoupling(points, cells, numCells, materials, dofNode, triplets, mass))
    return Status::Error("nodal pressure: cell with a non-positive Jacobian");
  const int n = 3 * numDofNodes;
  SparseMatrix G(static_cast<int>(pressureNodes), n);
  G.setFromTriplets(triplets.begin(), triplets.end());
  std::vector<Eigen::Triplet<double, int>>().swap(triplets);
  Eigen::VectorXd weight(pressureNodes);
  for (Eigen::Index i = 0; i < pressureNodes; ++i)
    weight[i] = mass[i] > 0.0 ? 1.0 / mass[i] : 0.0;
  const SparseMatrix WG = weight.asDiagonal() * G;
  const SparseMatrix Gt = G.transpose();
  SparseMatrix full = Gt * WG;
  upper = full.triangularView<Eigen::Upper>();
  upper.makeCompressed();
  return Status::Ok();
}

Status AddNodalPressureStiffness(SparseMatrix& upper, const RowVectors3d& points, const int* cells,
                                 Eigen::Index numCells, int nodesPerCell,
                                 const Materials& materials, const std::vector<int>& dofNode,
                                 int numDofNodes) {
  SparseMatrix pressure;
  const Status s = NodalPressureStiffness(points, cells, numCells, nodesPerCell, materials, dofNode,
                                          numDofNodes, pressure);
  if (!s)
    return s;
  SparseMatrix sum = upper + pressure;
  sum.makeCompressed();
  upper.swap(sum);
  return Status::Ok();
}

} // namespace faceplan
