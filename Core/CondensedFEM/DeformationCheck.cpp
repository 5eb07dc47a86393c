// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/DeformationCheck.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace faceplan {

namespace {

// Parameter counts above this make the bound's precompute (one field per parameter) and its
// looseness (Cauchy-Schwarz over many directions) not worth it: such mixed plans check every cell.
constexpr Eigen::Index kMaxBoundedParameters = 96;

} // namespace

Eigen::RowVector3d NodeDisplacement(const CondensedSystem& sys, int node,
                                    const Eigen::VectorXd& roi, const Eigen::VectorXd& freeValues) {
  const NodeLayout& layout = sys.layout;
  const int pos = layout.dofNode[node];
  if (pos < 0)
    return Eigen::RowVector3d::Zero();
  if (pos >= layout.freeNodes())
    return roi.segment<3>(3 * (pos - layout.freeNodes())).transpose();
  if (3 * pos + 2 >= freeValues.size())
    return Eigen::RowVector3d::Zero();
  const int slide = sys.slidingOfPosition.empty() ? -1 : sys.slidingOfPosition[pos];
  if (slide < 0)
    return freeValues.segment<3>(3 * pos).transpose();
  Eigen::Vector3d local = freeValues.segment<3>(3 * pos); // normal, tangent, tangent
  local[0] = sys.slidingRoiDof[slide] >= 0 ? roi[sys.slidingRoiDof[slide]] : 0.0;
  return (sys.slidingFrame[slide] * local).transpose();
}

double ScaledParameterNorm(const CondensedSystem& sys, const Eigen::VectorXd& p) {
  double sum = 0.0;
  const int segments = static_cast<int>(sys.segmentCentre.size());
  for (int s = 0; s < segments; ++s) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> affine(p.data() + 12 * s);
    const Eigen::Matrix3d a = affine.leftCols<3>();
    sum += sys.segmentLength[s] * sys.segmentLength[s] * a.squaredNorm() +
           (affine.col(3) + a * sys.segmentCentre[s]).squaredNorm();
  }
  sum += p.tail(p.size() - 12 * segments).squaredNorm();
  return std::sqrt(sum);
}

void BuildStrainBounds(CondensedSystem& sys) {
  sys.boundedCells.clear();
  sys.segmentCentre.clear();
  sys.segmentLength.clear();
  const Eigen::Index parameters = sys.response.cols();
  if (sys.method != SolveMethod::RigidSegments || !(sys.strainWarningLimit > 0.0) ||
      sys.checkableCells.empty() || parameters == 0 || parameters > kMaxBoundedParameters ||
      parameters < 12 * Eigen::Index(sys.segments))
    return;
  const RowVectors3d& points = sys.cornerMesh.points;
  const NodeSets& sets = sys.segmentSets;
  std::vector<Eigen::Vector3d> centre(sys.segments, Eigen::Vector3d::Zero());
  std::vector<double> length(sys.segments, 0.0);
  std::vector<int> count(sys.segments, 0);
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (const int s = sets.movableSegment[k]; s > 0) {
      centre[s - 1] += points.row(sets.movable[k]).transpose();
      ++count[s - 1];
    }
  for (int s = 0; s < sys.segments; ++s)
    centre[s] /= std::max(1, count[s]);
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (const int s = sets.movableSegment[k]; s > 0)
      length[s - 1] += (points.row(sets.movable[k]).transpose() - centre[s - 1]).squaredNorm();
  for (int s = 0; s < sys.segments; ++s) {
    length[s] = std::sqrt(length[s] / std::max(1, count[s]));
    if (!(length[s] > 0.0))
      length[s] = 1.0; // a one-node segment: any positive scale is a bound
  }

  // Inverse edge matrices of the cells the check evaluates (positive volume only, as it does), and
  // where each corner's displacement comes from in an edit.
  std::vector<int> keptRow(points.rows(), -1), movableRow(points.rows(), -1);
  for (size_t k = 0; k < sets.movable.size(); ++k)
    movableRow[sets.movable[k]] = static_cast<int>(k);
  for (size_t k = 0; k < sys.kept.size(); ++k)
    keptRow[sys.kept[k]] = static_cast<int>(k);
  std::vector<CondensedSystem::BoundedCell> bounded;
  for (int e : sys.checkableCells) {
    Eigen::Matrix3d edges;
    for (int j = 0; j < 3; ++j)
      edges.col(j) =
          (points.row(sys.cornerMesh.tets(e, j + 1)) - points.row(sys.cornerMesh.tets(e, 0)))
              .transpose();
    if (!(edges.determinant() > 0.0))
      continue;
    CondensedSystem::BoundedCell cell;
    cell.cell = e;
    cell.inverseEdges = edges.inverse();
    for (int j = 0; j < 4; ++j) {
      const int node = sys.cornerMesh.tets(e, j);
      cell.source[j] = keptRow[node] >= 0      ? keptRow[node]
                       : movableRow[node] >= 0 ? -(movableRow[node] + 2)
                                               : -1;
    }
    bounded.push_back(cell);
  }

  // One displacement field per rescaled parameter direction, through the solve's own mapping.
  const SparseMatrix basis = SegmentBasis(points, sets);
  std::vector<double> gain2(bounded.size(), 0.0);
  RowVectors3d field(points.rows(), 3);
  for (Eigen::Index j = 0; j < parameters; ++j) {
    Eigen::VectorXd p = Eigen::VectorXd::Zero(parameters);
    if (j < 12 * sys.segments) { // q_A = L A, q_b = b + A c  =>  A = q_A / L, b = q_b - A c
      const int s = static_cast<int>(j / 12), row = static_cast<int>(j % 12) / 4,
                col = static_cast<int>(j % 4);
      if (col < 3) {
        p[12 * s + 4 * row + col] = 1.0 / length[s];
        p[12 * s + 4 * row + 3] = -centre[s][col] / length[s];
      } else {
        p[12 * s + 4 * row + 3] = 1.0;
      }
    } else {
      p[j] = 1.0;
    }
    const Eigen::VectorXd movable = basis * p;
    const Eigen::VectorXd roi = sys.segmentToRoi * p;
    const Eigen::VectorXd keptFree = sys.response * p;
    field.setZero();
    for (size_t k = 0; k < sets.movable.size(); ++k)
      field.row(sets.movable[k]) = movable.segment<3>(3 * k).transpose();
    for (int node : sys.kept)
      field.row(node) = NodeDisplacement(sys, node, roi, keptFree);
    for (size_t c = 0; c < bounded.size(); ++c) {
      Eigen::Matrix3d du;
      const int e = bounded[c].cell;
      for (int i = 0; i < 3; ++i)
        du.col(i) =
            (field.row(sys.cornerMesh.tets(e, i + 1)) - field.row(sys.cornerMesh.tets(e, 0)))
                .transpose();
      gain2[c] += (du * bounded[c].inverseEdges).squaredNorm();
    }
  }
  std::vector<size_t> order(bounded.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return gain2[a] > gain2[b]; });
  sys.boundedCells.reserve(bounded.size());
  for (size_t c : order) {
    sys.boundedCells.push_back(bounded[c]);
    sys.boundedCells.back().gain = std::sqrt(gain2[c]);
  }
  sys.segmentCentre = std::move(centre);
  sys.segmentLength = std::move(length);
}

DeformationReport CheckBoundedCells(const CondensedSystem& sys, const Eigen::VectorXd& p,
                                    const std::vector<SegmentTransform>& transforms,
                                    const RowVectors3d& movableDisplacement,
                                    const RowVectors3d& keptDisplacement,
                                    std::vector<std::string>& warnings) {
  DeformationReport report;
  const double scale =
      ScaledParameterNorm(sys, p) * (1.0 + 1e-9); // margin over the bound's rounding
  const RowVectors3d& points = sys.cornerMesh.points;
  const NodeSets& sets = sys.segmentSets;
  auto cornerDisplacement = [&](int source) -> Eigen::Vector3d {
    if (source >= 0)
      return keptDisplacement.row(source).transpose();
    if (source == -1)
      return Eigen::Vector3d::Zero();
    const int m = -source - 2;
    const int s = sets.movableSegment[m];
    if (s == 0)
      return movableDisplacement.row(m).transpose();
    const Eigen::Vector3d x = points.row(sets.movable[m]).transpose();
    return transforms[s - 1].leftCols<3>() * x + transforms[s - 1].col(3) - x;
  };
  for (const CondensedSystem::BoundedCell& cell : sys.boundedCells) {
    const double bound = cell.gain * scale;
    if (bound < report.largestStrain && bound < 1.0)
      break; // no later cell can exceed the largest strain found or invert
    Eigen::Matrix3d du;
    const Eigen::Vector3d u0 = cornerDisplacement(cell.source[0]);
    for (int j = 0; j < 3; ++j)
      du.col(j) = cornerDisplacement(cell.source[j + 1]) - u0;
    AddCellDeformation(report, cell.cell, du * cell.inverseEdges);
  }
  // Cells were visited by bound; list the inverted ones in mesh order, as CheckDeformation does.
  std::sort(report.invertedCells.begin(), report.invertedCells.end());
  AppendDeformationWarnings(report, sys.strainWarningLimit, warnings);
  return report;
}

} // namespace faceplan
