// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Step 2 of CondensedFEMDeform for the Bone port: several connections (a bimaxillary plan: maxilla
// and mandible, each from its own Osteotomy or BezierCut) become one bone, and the bone's rigid
// segments (point array SegmentId, field data SegmentTransform) are read and checked.
// Private to FacePlan::Filters; each connection is validated before.
#include "Common/Status.h"
#include "CondensedFEM/RigidSegments.h"

#include "vtkSmartPointer.h"

#include <string>
#include <vector>

class vtkPointSet;

namespace faceplan {
namespace fem_filter {

// A fixed bone (a connection without the point array Displacement: bone that stays put) as a
// shallow copy of `bone` with a zero 3-component Displacement. The input is not modified.
vtkSmartPointer<vtkPointSet> WithZeroDisplacement(vtkPointSet* bone);

// One bone from the connections: points and cells appended, SegmentId of each connection offset
// by the segments of the ones before it, SegmentTransform concatenated in that order; a point
// array one connection lacks is filled (ROIMask 1, SegmentId 0, Sliding 0, Released 0). One
// connection is returned as it is.
vtkSmartPointer<vtkPointSet> MergeBones(const std::vector<vtkPointSet*>& bones);

// The bone's rigid segments as Core numbers them: `segmentOfPoint` (bone point -> 1..s, 0 when the
// point is on no rigid segment or its segment's transform is NaN) and one transform per segment.
// `usable` is false, with `whyNot`, when the bone has no segments or its Displacement does not
// follow a segment's transform (checked by Core's CheckSegmentDisplacements).
struct BoneSegments {
  bool usable = false;
  std::string whyNot;
  std::vector<int> segmentOfPoint;
  std::vector<SegmentTransform> transforms;
};
// `undeformed`: the bone's undeformed points, 3 per point (BoneInput::undeformed).
BoneSegments ReadBoneSegments(vtkPointSet* bone, const std::vector<double>& undeformed);

} // namespace fem_filter
} // namespace faceplan
