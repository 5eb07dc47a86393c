#pragma once
// Step 3 of CondensedFEMDeform: ties soft-tissue boundary nodes to the bone. Each tissue boundary
// node within ContactDistance of the undeformed bone (bone points minus Displacement) is tied to
// its closest point there, found with a VTK cell locator; its displacement is the bone's
// Displacement interpolated at that point. Tied nodes where the bone's ROIMask is 0 stay fixed.
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
  std::vector<char> movable; // 1 when the bone's ROIMask at the closest point is > 0
};

// The contact map for one tissue and bone, rebuilt only when what it depends on changed: the
// undeformed bone's points, its cells, its ROIMask, the tissue's points and boundary nodes, and
// the distance. A cut edit (new Displacement on the same bone) keeps it.
class ContactCache {
public:
  Status update(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                vtkPointSet* bone, double contactDistance);
  const ContactMap& map() const { return map_; }
  void clear() { valid_ = false; }

private:
  struct Key {
    std::vector<double> undeformedBone, mask, tissuePoints;
    std::vector<vtkIdType> boneCells, tissueBoundary;
    double distance = -1.0;
  };
  static Key MakeKey(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                     vtkPointSet* bone, double contactDistance);
  bool valid_ = false;
  Key key_;
  ContactMap map_;
};

// The node sets of the solve: tied nodes constrained (movable where the ROI moves), the tissue
// boundary kept.
NodeSets MakeNodeSets(const ContactMap& map, const std::vector<vtkIdType>& tissueBoundary);

// The bone's displacement at each movable tied node, in NodeSets::movable order.
Displacements MovableDisplacements(const ContactMap& map, vtkDataArray* boneDisplacement);

} // namespace fem_filter
} // namespace faceplan
