#include "FacePlanContact.h"

#include "vtkCell.h"
#include "vtkDataArray.h"
#include "vtkGenericCell.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkStaticCellLocator.h"

#include <cmath>

namespace faceplan {
namespace vtkcontact {

bool BuildContactMap(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                     vtkPointSet* bone, vtkDataArray* boneDisplacement, vtkDataArray* roiMask,
                     double contactDistance, ContactMap& map, std::string& why) {
  map = ContactMap();
  if (bone->GetNumberOfCells() == 0) {
    why = "the Bone input has no cells to make contact with";
    return false;
  }
  // The undeformed bone: the contact is defined before the operation moved it.
  vtkSmartPointer<vtkPointSet> undeformed;
  undeformed.TakeReference(vtkPointSet::SafeDownCast(bone->NewInstance()));
  undeformed->CopyStructure(bone);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(bone->GetNumberOfPoints());
  for (vtkIdType i = 0; i < bone->GetNumberOfPoints(); ++i) {
    double p[3], d[3];
    bone->GetPoint(i, p);
    boneDisplacement->GetTuple(i, d);
    points->SetPoint(i, p[0] - d[0], p[1] - d[1], p[2] - d[2]);
  }
  undeformed->SetPoints(points);

  vtkNew<vtkStaticCellLocator> locator;
  locator->SetDataSet(undeformed);
  locator->BuildLocator();
  vtkNew<vtkGenericCell> cell;
  std::vector<double> weights(64);
  map.weightStart.push_back(0);
  for (vtkIdType node : tissueBoundary) {
    double x[3], closest[3], dist2, pcoords[3];
    vtkIdType cellId;
    int subId, inside;
    tissue->GetPoint(node, x);
    if (!locator->FindClosestPointWithinRadius(x, contactDistance, closest, cell, cellId, subId, dist2, inside))
      continue;
    // The locator uses `cell` as scratch space: fetch the closest cell itself.
    undeformed->GetCell(cellId, cell);
    const vtkIdType n = cell->GetNumberOfPoints();
    if (static_cast<size_t>(n) > weights.size()) weights.resize(n);
    double evalClosest[3], evalDist2;
    cell->EvaluatePosition(closest, evalClosest, subId, pcoords, evalDist2, weights.data());
    double mask = 1.0;
    if (roiMask) {
      mask = 0.0;
      for (vtkIdType k = 0; k < n; ++k) mask += weights[k] * roiMask->GetComponent(cell->GetPointId(k), 0);
    }
    map.tiedNodes.push_back(static_cast<int>(node));
    map.movable.push_back(mask > 1e-12 ? 1 : 0);
    for (vtkIdType k = 0; k < n; ++k) {
      map.bonePointIds.push_back(cell->GetPointId(k));
      map.weights.push_back(weights[k]);
    }
    map.weightStart.push_back(static_cast<vtkIdType>(map.weights.size()));
  }
  return true;
}

void InterpolateDisplacement(const ContactMap& map, vtkDataArray* boneDisplacement,
                             std::vector<double>& out) {
  out.assign(3 * map.tiedNodes.size(), 0.0);
  for (size_t t = 0; t < map.tiedNodes.size(); ++t) {
    for (vtkIdType k = map.weightStart[t]; k < map.weightStart[t + 1]; ++k) {
      double d[3];
      boneDisplacement->GetTuple(map.bonePointIds[k], d);
      for (int c = 0; c < 3; ++c) out[3 * t + c] += map.weights[k] * d[c];
    }
  }
}

} // namespace vtkcontact
} // namespace faceplan
