#pragma once
// Ties soft-tissue boundary nodes to a bone surface (private to FacePlan::Filters): each tissue
// boundary node within ContactDistance of the undeformed bone (bone points minus Displacement) is
// tied to its closest point there, found with a VTK cell locator; its displacement is the bone's
// Displacement interpolated at that point. Geometry lookup only; no numerics beyond interpolation.
#include <string>
#include <vector>

#include "vtkType.h"

class vtkPointSet;
class vtkDataArray;

namespace faceplan {
namespace vtkcontact {

struct ContactMap {
  std::vector<int> tiedNodes;        // tissue point ids
  std::vector<vtkIdType> weightStart; // tiedNodes.size() + 1 offsets into ids/weights
  std::vector<vtkIdType> bonePointIds;
  std::vector<double> weights;
  std::vector<char> movable;         // 1 when the bone's ROIMask at the closest point is > 0
};

// Builds the map. `tissueBoundary` lists candidate tissue points. Returns false with `why` set.
bool BuildContactMap(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                     vtkPointSet* bone, vtkDataArray* boneDisplacement, vtkDataArray* roiMask,
                     double contactDistance, ContactMap& map, std::string& why);

// The bone's displacement interpolated at each tied node's closest point (tied x 3, row-major).
void InterpolateDisplacement(const ContactMap& map, vtkDataArray* boneDisplacement,
                             std::vector<double>& out);

} // namespace vtkcontact
} // namespace faceplan
