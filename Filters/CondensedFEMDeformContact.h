// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Step 3 of CondensedFEMDeform: ties soft-tissue boundary nodes to the bone. Each tissue boundary
// node within ContactDistance of the undeformed bone (bone points minus Displacement) is tied to
// its closest point there, found with a VTK cell locator; its displacement is the bone's
// Displacement interpolated at that point. Tied nodes where the bone's ROIMask is 0 stay fixed.
// Each tied node also records the bone point that weighs most at its closest point (its SegmentId
// and Sliding flag count), the bone's normal there, and whether it is released: that bone point is
// flagged by the bone's point array Released (> 0: the surgeon detached the tissue there), or it
// lies within ReleaseDistance of a bone point of another region (another SegmentId, or the other
// side of the ROIMask boundary), that is of a cut line, a cut face or the ROI's boundary.
// Private to FacePlan::Filters; inputs are validated before.
#include "Common/Status.h"
#include "Mesh/NodeSets.h"
#include "Mesh/TetMesh.h"

#include "vtkType.h"

#include <vector>

class vtkDataArray;
class vtkPointSet;

namespace faceplan {
namespace fem_filter {

struct ContactMap {
  std::vector<int> tiedNodes;         // tissue point ids
  std::vector<vtkIdType> weightStart; // tiedNodes.size() + 1 offsets into ids/weights
  std::vector<vtkIdType> bonePointIds;
  std::vector<double> weights;
  std::vector<char> movable;               // 1 when the bone's ROIMask at the closest point is > 0
  std::vector<vtkIdType> nearestBonePoint; // the closest cell's point of largest weight
  std::vector<double> normals;             // 3 per tied node: the closest cell's unit normal
  std::vector<char> released; // 1 when flagged Released or within ReleaseDistance of another region
};

enum class ContactModelChoice { Tied = 0, Sliding = 1, ByArray = 2, Auto = 3 };

// The contact model an update uses: Auto is ByArray where the bone carries a Sliding array (an
// Osteotomy operation preset marks the teeth), Tied otherwise.
ContactModelChoice ResolveContactModel(ContactModelChoice chosen, bool boneHasSliding);
const char* ContactModelName(ContactModelChoice model);

// The contact map between one tissue and bone, kept between updates: CondensedFEMDeform rebuilds
// it when BoneInput::contactChanged says that what it depends on changed (the tissue, the
// distances, the bone's cells, ROIMask, SegmentId and Released, the undeformed bone); a cut edit
// (new Displacement on the same bone) keeps it.
class ContactCache {
public:
  // `undeformed`: the bone's undeformed points, 3 per point (BoneInput::undeformed).
  Status build(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary, vtkPointSet* bone,
               const std::vector<double>& undeformed, double contactDistance,
               double releaseDistance);
  const ContactMap& map() const { return map_; }

private:
  ContactMap map_;
};

// The node sets of the solve: tied nodes that are not released constrained (movable where the ROI
// moves), the tissue boundary kept. Sliding nodes by the contact model (ByArray: the bone point
// array Sliding > 0 at the node's bone point), with the bone's normal. `segmentOfBonePoint`, when
// not empty, gives movable nodes their rigid segment.
NodeSets MakeNodeSets(const ContactMap& map, const std::vector<vtkIdType>& tissueBoundary,
                      ContactModelChoice model, vtkDataArray* slidingFlags,
                      const std::vector<int>& segmentOfBonePoint);

// The bone's displacement at each movable tied node, in NodeSets::movable order.
RowVectors3d MovableDisplacements(const ContactMap& map, vtkDataArray* boneDisplacement);

// The number of tied nodes that were released (by ReleaseDistance or the Released array).
size_t ReleasedCount(const ContactMap& map);

} // namespace fem_filter
} // namespace faceplan
