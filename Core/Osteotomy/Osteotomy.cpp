// SPDX-License-Identifier: BSD-3-Clause
#include "Osteotomy/Osteotomy.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <set>

namespace faceplan {

namespace {

Status ValidateBone(const OsteotomyBone& bone) {
  const Eigen::Index n = bone.mesh.numPoints();
  const std::size_t un = static_cast<std::size_t>(n);
  if (n == 0)
    return Status::Error("the bone has no points");
  if (bone.mesh.numCells() == 0)
    return Status::Error("the bone has no triangles");
  for (std::int64_t c = 0; c < bone.mesh.numCells(); ++c) {
    if (bone.mesh.cellSize(c) != 3)
      return Status::Error("cell " + std::to_string(c) + " of the bone is not a triangle");
    for (int k = 0; k < 3; ++k) {
      const std::int64_t id = bone.mesh.cell(c)[k];
      if (id < 0 || id >= n)
        return Status::Error("cell " + std::to_string(c) + " uses a point id out of range");
    }
  }
  if (!bone.mesh.points.allFinite())
    return Status::Error("the bone has a NaN or infinite coordinate");
  if (bone.displacement.rows() != n)
    return Status::Error("the displacement does not have one row per point");
  if (!bone.displacement.allFinite())
    return Status::Error("the bone's Displacement has a NaN or infinite value");
  if (bone.segmentId.size() != un || bone.roiMask.size() != un || bone.moves.size() != un)
    return Status::Error("segment ids, ROI mask and segment flags need one value per point");
  if (std::any_of(bone.segmentId.begin(), bone.segmentId.end(), [](int s) { return s < 0; }))
    return Status::Error("the bone's SegmentId has a negative value");
  const auto moving = std::count(bone.moves.begin(), bone.moves.end(), std::uint8_t(1));
  if (moving == 0)
    return Status::Error("the cut leaves no vertex of the bone on the moving side");
  if (moving == n)
    return Status::Error("the cut leaves no vertex of the bone on the fixed side");
  return Status::Ok();
}

double BoundingDiagonal(const RowVectors3d& p) {
  return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
}

} // namespace

Eigen::Vector3d SelectedSurfaceCentroid(const SurfaceMesh& mesh,
                                        const std::vector<std::uint8_t>& selected) {
  Eigen::Vector3d weighted = Eigen::Vector3d::Zero();
  double area = 0.0;
  for (std::int64_t c = 0; c < mesh.numCells(); ++c) {
    if (mesh.cellSize(c) != 3)
      continue;
    const std::int64_t* ids = mesh.cell(c);
    if (!selected[ids[0]] || !selected[ids[1]] || !selected[ids[2]])
      continue;
    const Eigen::Vector3d a = mesh.points.row(ids[0]), b = mesh.points.row(ids[1]),
                          d = mesh.points.row(ids[2]);
    const double w = 0.5 * (b - a).cross(d - a).norm();
    weighted += w * (a + b + d) / 3.0;
    area += w;
  }
  if (area > 0.0)
    return weighted / area;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0.0;
  for (Eigen::Index i = 0; i < mesh.numPoints(); ++i)
    if (selected[static_cast<std::size_t>(i)]) {
      sum += mesh.points.row(i).transpose();
      count += 1.0;
    }
  return count > 0.0 ? Eigen::Vector3d(sum / count) : sum;
}

Status MoveSegment(const OsteotomyBone& bone, const OsteotomyMove& request,
                   OsteotomyResult& result) {
  result = OsteotomyResult();
  if (Status s = ValidateBone(bone); !s)
    return s;
  const Eigen::Index n = bone.mesh.numPoints();

  SegmentMove move = request.move;
  if (request.pivotMode == PivotMode::SegmentCentroid)
    move.pivot = SelectedSurfaceCentroid(bone.mesh, bone.moves);
  if (Status s = RigidMotion(move, result.motion); !s)
    return s;
  result.pivot = move.pivot;

  const int inputSegments = *std::max_element(bone.segmentId.begin(), bone.segmentId.end());
  result.newSegmentId = inputSegments + 1;
  std::vector<AffineMap> transforms =
      UnpackSegmentTransforms(bone.segmentTransforms, inputSegments);
  result.segmentNotes.assign(static_cast<std::size_t>(inputSegments), std::string());
  for (int s = 0; s < inputSegments; ++s) {
    if (static_cast<std::size_t>(s) < bone.segmentNotes.size())
      result.segmentNotes[s] = bone.segmentNotes[s];
    if (!IsFinite(transforms[s]) && result.segmentNotes[s].empty())
      result.segmentNotes[s] =
          "no rigid transform from the undeformed bone is known for this segment";
  }

  // Where the new segment's points came from: one rigid map from the undeformed bone that every one
  // of them follows (an earlier segment's, or the identity for unmoved bone), or none.
  const double tolerance = 1e-9 * std::max(BoundingDiagonal(bone.mesh.points), 1e-300);
  std::set<int> sources;
  for (Eigen::Index i = 0; i < n; ++i)
    if (bone.moves[static_cast<std::size_t>(i)])
      sources.insert(bone.segmentId[static_cast<std::size_t>(i)]);
  AffineMap before = NotRigid();
  for (int source : sources) {
    AffineMap candidate = AffineMap::Zero();
    candidate.leftCols<3>().setIdentity();
    if (source > 0)
      candidate = transforms[source - 1];
    if (!IsFinite(candidate))
      continue;
    bool follows = true;
    for (Eigen::Index i = 0; i < n && follows; ++i) {
      if (!bone.moves[static_cast<std::size_t>(i)])
        continue;
      const Eigen::Vector3d p = bone.mesh.points.row(i),
                            undeformed = p - bone.displacement.row(i).transpose();
      follows = (Apply(candidate, undeformed) - p).norm() <= tolerance;
    }
    if (follows) {
      before = candidate;
      break;
    }
  }

  result.points = bone.mesh.points;
  result.displacement = bone.displacement;
  result.segmentId = bone.segmentId;
  result.roiMask = bone.roiMask;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!bone.moves[static_cast<std::size_t>(i)])
      continue;
    const Eigen::Vector3d p = bone.mesh.points.row(i);
    const Eigen::Vector3d moved = Apply(result.motion, p);
    result.points.row(i) = moved.transpose();
    result.displacement.row(i) += (moved - p).transpose();
    result.segmentId[static_cast<std::size_t>(i)] = result.newSegmentId;
    result.roiMask[static_cast<std::size_t>(i)] = 1;
  }
  if (IsFinite(before)) {
    transforms.push_back(Compose(result.motion, before));
    result.segmentNotes.emplace_back();
  } else {
    transforms.push_back(NotRigid());
    result.segmentNotes.emplace_back(
        "the segment's points had not moved rigidly together before this osteotomy (for example a "
        "Bezier cut reshaped them), so no single rigid transform maps the undeformed bone onto it; "
        "its Displacement is still exact");
  }
  result.segmentTransforms = PackSegmentTransforms(transforms);
  if (!result.points.allFinite() || !result.displacement.allFinite())
    return Status::Error("the moved segment has a non-finite coordinate");
  return Status::Ok();
}

} // namespace faceplan
