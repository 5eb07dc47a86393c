// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// An osteotomy's move: a bone already split along the cut (the filter does the split and the caps)
// gets one of its parts, the new segment, moved rigidly. Keeps the bookkeeping that lets several
// osteotomies and Bezier cuts compose: cumulative displacement from the undeformed bone, ROI mask,
// segment ids and, per segment, the rigid transform from the undeformed bone when there is one.
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"
#include "Osteotomy/SegmentTransform.h"

#include <cstdint>
#include <string>
#include <vector>

namespace faceplan {

struct OsteotomyBone {
  SurfaceMesh mesh;                      // triangles, current positions
  RowVectors3d displacement;             // n x 3: motion so far from the undeformed bone
  std::vector<int> segmentId;            // n: 0 = moved by no osteotomy
  std::vector<std::uint8_t> roiMask;     // n
  std::vector<double> segmentTransforms; // 12 per segment id 1, 2, ... (may be short or empty)
  std::vector<std::string> segmentNotes; // one per segment id 1, 2, ... (may be short or empty)
  std::vector<std::uint8_t> moves;       // n: 1 on the points of the new segment
};

enum class PivotMode { SegmentCentroid, Custom };

struct OsteotomyMove {
  SegmentMove move; // move.pivot is used with PivotMode::Custom
  PivotMode pivotMode =
      PivotMode::SegmentCentroid; // centroid: area-weighted, of the segment's surface
};

struct OsteotomyResult {
  RowVectors3d points;                   // n x 3, the new segment moved
  RowVectors3d displacement;             // n x 3, cumulative from the undeformed bone
  std::vector<int> segmentId;            // n; the new segment's points get newSegmentId
  std::vector<std::uint8_t> roiMask;     // n; 1 on the new segment, else the input's
  std::vector<double> segmentTransforms; // 12 * newSegmentId (NaN for a segment that is not rigid)
  std::vector<std::string> segmentNotes; // newSegmentId entries; "" for a rigid segment
  int newSegmentId = 0;
  AffineMap motion = AffineMap::Zero(); // this osteotomy's move, in current coordinates
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
};

// Fails (naming the problem) on cells that are not triangles, non-finite coordinates or
// displacements, mismatched array sizes, negative segment ids, an empty new segment or an empty
// rest, and a non-finite move.
Status MoveSegment(const OsteotomyBone& bone, const OsteotomyMove& move, OsteotomyResult& result);

// The area-weighted centroid of the triangles whose three points all have selected[i] != 0.
// Falls back to the mean of the selected points when those triangles have no area.
Eigen::Vector3d SelectedSurfaceCentroid(const SurfaceMesh& mesh,
                                        const std::vector<std::uint8_t>& selected);

} // namespace faceplan
