// SPDX-License-Identifier: BSD-3-Clause
// The osteotomy's planes and transforms on random input: cut planes (any values, NaN included)
// over a small bone, the sides and convex pieces, the rigid move of the segment, and the packing
// of segment transforms. Promises checked: no crash; accepted planes have unit normals; a move
// that succeeds is rigid (orthonormal, det +1), finite, moves exactly the segment's points and
// keeps the cumulative displacement consistent.
#include "FuzzBytes.h"

#include "Osteotomy/CutPlanes.h"
#include "Osteotomy/Osteotomy.h"
#include "Osteotomy/SegmentTransform.h"
#include "Support/FaceplanTestMeshes.h"

#include <cmath>
#include <cstdint>
#include <vector>

using namespace faceplan;
using faceplan::fuzz::FuzzBytes;
using faceplan::fuzz::Violation;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const SurfaceMesh bone = testmesh::Icosphere(1, 10.0);
  FuzzBytes in(data, size);
  const Eigen::Index n = bone.numPoints();

  std::vector<CutPlane> planes(std::size_t(in.range(0, 3)));
  const bool special = in.byte() < 32;
  for (CutPlane& plane : planes) {
    for (int c = 0; c < 3; ++c) {
      plane.origin[c] = special ? in.number(5.0) : in.scaled(12.0);
      plane.normal[c] = special ? in.number(1.0) : in.scaled(1.0);
    }
  }
  const bool insideOut = in.flag();
  const Status normalized = NormalizeCutPlanes(planes);
  if (!normalized) {
    if (normalized.message.empty())
      Violation("a plane error without a message");
    return 0;
  }
  for (const CutPlane& plane : planes)
    if (!plane.origin.allFinite() || !(std::abs(plane.normal.norm() - 1.0) < 1e-12))
      Violation("an accepted plane is not finite with a unit normal");
  const std::vector<ConvexPiece> pieces = ConvexPiecesOfCut(planes, insideOut);
  for (const ConvexPiece& piece : pieces)
    if (piece.bounds.size() > planes.size())
      Violation("a convex piece with more bounds than planes");
  if (!planes.empty()) {
    const std::array<double, 6> box = {-12, 12, -12, 12, -12, 12};
    for (const Eigen::Vector3d& corner : PlaneBoxSection(planes.front(), box))
      if (!corner.allFinite())
        Violation("a plane-box section corner is not finite");
  }
  std::vector<std::uint8_t> side;
  const Status classified = ClassifyCutSides(bone.points, planes, insideOut, side);
  if (!classified)
    return 0;

  OsteotomyBone input;
  input.mesh = bone;
  input.displacement = RowVectors3d::Zero(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    if (in.flag())
      input.displacement.row(i) << in.scaled(1.0), in.scaled(1.0), in.scaled(1.0);
  input.segmentId.assign(std::size_t(n), 0);
  for (auto& id : input.segmentId)
    id = in.byte() % 3;
  input.roiMask.assign(std::size_t(n), 0);
  input.segmentTransforms.resize(std::size_t(in.range(0, 30)));
  for (double& v : input.segmentTransforms)
    v = in.flag() ? in.number(1.0) : in.scaled(1.0);
  input.moves = side;
  OsteotomyMove move;
  for (int c = 0; c < 3; ++c) {
    move.move.translation[c] = special ? in.number(2.0) : in.scaled(5.0);
    move.move.rotationDegrees[c] = special ? in.number(30.0) : in.scaled(180.0);
    move.move.pivot[c] = in.scaled(10.0);
  }
  move.pivotMode = in.flag() ? PivotMode::Custom : PivotMode::SegmentCentroid;

  OsteotomyResult result;
  const Status moved = MoveSegment(input, move, result);
  if (!moved) {
    if (moved.message.empty())
      Violation("a move error without a message");
    return 0;
  }
  const Eigen::Matrix3d R = result.motion.leftCols<3>();
  if (!IsFinite(result.motion) || !(R.transpose() * R).isIdentity(1e-9) ||
      !(std::abs(R.determinant() - 1.0) < 1e-9))
    Violation("the segment's motion is not a finite rotation");
  if (result.points.rows() != n || !result.points.allFinite() || !result.displacement.allFinite())
    Violation("the moved bone is not finite or changed size");
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x = bone.points.row(i).transpose();
    const Eigen::Vector3d expected = side[std::size_t(i)] ? Apply(result.motion, x) : x;
    if (!((result.points.row(i).transpose() - expected).norm() <= 1e-9 * (1.0 + expected.norm())))
      Violation("a point moved other than by the segment's motion");
    const Eigen::Vector3d step = result.points.row(i) - bone.points.row(i);
    if (!((result.displacement.row(i) - input.displacement.row(i) - step.transpose()).norm() <=
          1e-9 * (1.0 + expected.norm())))
      Violation("the cumulative displacement does not add the move");
  }
  const std::vector<AffineMap> unpacked =
      UnpackSegmentTransforms(result.segmentTransforms, result.newSegmentId);
  if (int(unpacked.size()) != result.newSegmentId)
    Violation("segment transforms lost in packing");
  return 0;
}
