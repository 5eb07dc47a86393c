// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/RigidSegments.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace faceplan {

int SegmentCount(const NodeSets& sets) {
  int count = 0;
  for (int segment : sets.movableSegment)
    count = std::max(count, segment);
  return count;
}

Status CheckSegmentDisplacements(const RowVectors3d& points, const NodeSets& sets,
                                 const std::vector<SegmentTransform>& transforms,
                                 const RowVectors3d& movableDisplacement, double meshExtent) {
  const int segments = SegmentCount(sets);
  if (static_cast<int>(transforms.size()) != segments)
    return Status::Error("expected " + std::to_string(segments) + " segment transforms, got " +
                         std::to_string(transforms.size()));
  for (int s = 0; s < segments; ++s)
    if (!transforms[s].allFinite())
      return Status::Error("the transform of segment " + std::to_string(s + 1) + " is not finite");
  if (movableDisplacement.rows() != static_cast<Eigen::Index>(sets.movable.size()))
    return Status::Error("expected one displacement per movable node");
  const double extent = meshExtent >= 0.0 ? meshExtent
                        : points.rows() > 0
                            ? (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm()
                            : 1.0;
  std::vector<double> largest(segments + 1, 0.0);
  for (size_t k = 0; k < sets.movableSegment.size(); ++k)
    largest[sets.movableSegment[k]] =
        std::max(largest[sets.movableSegment[k]], movableDisplacement.row(k).norm());
  for (size_t k = 0; k < sets.movableSegment.size(); ++k) {
    const int s = sets.movableSegment[k];
    if (s == 0)
      continue;
    const Eigen::Vector3d x = points.row(sets.movable[k]).transpose();
    const Eigen::Vector3d expected =
        transforms[s - 1].leftCols<3>() * x + transforms[s - 1].col(3) - x;
    const double mismatch = (movableDisplacement.row(k).transpose() - expected).norm();
    const double tolerance = 1e-8 * std::max(largest[s], 1e-12 * extent);
    if (!(mismatch <= tolerance)) {
      std::ostringstream msg;
      msg.precision(3);
      msg << "the displacement of node " << sets.movable[k] << " (segment " << s << ") differs by "
          << mismatch << " from its segment's transform (tolerance " << tolerance << ")";
      return Status::Error(msg.str());
    }
  }
  return Status::Ok();
}

SparseMatrix SegmentBasis(const RowVectors3d& points, const NodeSets& sets) {
  const int segments = SegmentCount(sets);
  const Eigen::Index movable = static_cast<Eigen::Index>(sets.movable.size());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::Index general = 12 * segments;
  for (Eigen::Index k = 0; k < movable; ++k) {
    const int s = sets.movableSegment.empty() ? 0 : sets.movableSegment[k];
    if (s == 0) {
      for (int i = 0; i < 3; ++i)
        entries.emplace_back(3 * k + i, general + i, 1.0);
      general += 3;
      continue;
    }
    const Eigen::RowVector3d x = points.row(sets.movable[k]);
    const Eigen::Index first = 12 * (s - 1);
    for (int i = 0; i < 3; ++i) { // u_i = sum_j A_ij x_j + b_i
      for (int j = 0; j < 3; ++j)
        entries.emplace_back(3 * k + i, first + 4 * i + j, x[j]);
      entries.emplace_back(3 * k + i, first + 4 * i + 3, 1.0);
    }
  }
  SparseMatrix basis(3 * movable, general);
  basis.setFromTriplets(entries.begin(), entries.end());
  return basis;
}

Eigen::VectorXd SegmentParameters(const NodeSets& sets,
                                  const std::vector<SegmentTransform>& transforms,
                                  const RowVectors3d& movableDisplacement) {
  const int segments = static_cast<int>(transforms.size());
  Eigen::Index generalNodes = 0;
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (sets.movableSegment.empty() || sets.movableSegment[k] == 0)
      ++generalNodes;
  Eigen::VectorXd p(12 * segments + 3 * generalNodes);
  for (int s = 0; s < segments; ++s) {
    SegmentTransform affine = transforms[s];
    affine.leftCols<3>() -= Eigen::Matrix3d::Identity();
    p.segment<12>(12 * s) = Eigen::Map<const Eigen::Matrix<double, 12, 1>>(affine.data());
  }
  Eigen::Index slot = 12 * segments;
  for (size_t k = 0; k < sets.movable.size(); ++k)
    if (sets.movableSegment.empty() || sets.movableSegment[k] == 0) {
      p.segment<3>(slot) = movableDisplacement.row(static_cast<Eigen::Index>(k)).transpose();
      slot += 3;
    }
  return p;
}

RowVectors3d FollowSegments(const RowVectors3d& points, const NodeSets& sets,
                            const std::vector<SegmentTransform>& transforms,
                            const RowVectors3d& movableDisplacement) {
  RowVectors3d out = movableDisplacement;
  for (size_t k = 0; k < sets.movableSegment.size(); ++k) {
    const int s = sets.movableSegment[k];
    if (s <= 0 || s > static_cast<int>(transforms.size()))
      continue;
    const Eigen::Vector3d x = points.row(sets.movable[k]).transpose();
    out.row(static_cast<Eigen::Index>(k)) =
        (transforms[s - 1].leftCols<3>() * x + transforms[s - 1].col(3) - x).transpose();
  }
  return out;
}

} // namespace faceplan
