// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformContact.h"

#include "FacePlanUndeformedBone.h"

#include "vtkCell.h"
#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkGenericCell.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkStaticCellLocator.h"

#include "vtkPolyData.h"
#include "vtkPolygon.h"
#include "vtkStaticPointLocator.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace faceplan {
namespace fem_filter {

namespace {

// Region of a bone point for the release: its SegmentId and its side of the ROIMask boundary.
long RegionOf(vtkPointSet* bone, vtkIdType point) {
  vtkDataArray* ids = bone->GetPointData()->GetArray("SegmentId");
  vtkDataArray* mask = bone->GetPointData()->GetArray("ROIMask");
  const long segment = ids ? std::lround(ids->GetComponent(point, 0)) : 0;
  const long side = mask && mask->GetComponent(point, 0) > 0.0 ? 1 : 0;
  return 2 * segment + side;
}

// Marks tied nodes whose bone point the bone's Released array flags (tissue the surgeon detached
// there) and those within `releaseDistance` of an undeformed bone point of another region.
void MarkReleased(vtkPointSet* tissue, vtkPointSet* undeformed, vtkPointSet* bone,
                  double releaseDistance, ContactMap& map) {
  map.released.assign(map.tiedNodes.size(), 0);
  if (vtkDataArray* flags = bone->GetPointData()->GetArray("Released"))
    for (size_t t = 0; t < map.tiedNodes.size(); ++t)
      if (flags->GetComponent(map.nearestBonePoint[t], 0) > 0.0)
        map.released[t] = 1;
  if (!(releaseDistance > 0.0))
    return;
  std::map<long, vtkSmartPointer<vtkPolyData>> regions;
  for (vtkIdType i = 0; i < undeformed->GetNumberOfPoints(); ++i) {
    vtkSmartPointer<vtkPolyData>& region = regions[RegionOf(bone, i)];
    if (!region) {
      region = vtkSmartPointer<vtkPolyData>::New();
      vtkNew<vtkPoints> points;
      points->SetDataTypeToDouble();
      region->SetPoints(points);
    }
    region->GetPoints()->InsertNextPoint(undeformed->GetPoint(i));
  }
  if (regions.size() < 2)
    return;
  std::map<long, vtkSmartPointer<vtkStaticPointLocator>> locators;
  for (auto& [label, points] : regions) {
    auto locator = vtkSmartPointer<vtkStaticPointLocator>::New();
    locator->SetDataSet(points);
    locator->BuildLocator();
    locators[label] = locator;
  }
  for (size_t t = 0; t < map.tiedNodes.size(); ++t) {
    const long own = RegionOf(bone, map.nearestBonePoint[t]);
    double x[3], dist2;
    tissue->GetPoint(map.tiedNodes[t], x);
    for (auto& [label, locator] : locators)
      if (!map.released[t] && label != own &&
          locator->FindClosestPointWithinRadius(releaseDistance, x, dist2) >= 0) {
        map.released[t] = 1;
        break;
      }
  }
}

ContactMap BuildContactMap(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                           vtkPointSet* bone, const std::vector<double>& undeformedPoints,
                           double contactDistance, double releaseDistance) {
  vtkDataArray* roiMask = bone->GetPointData()->GetArray("ROIMask");
  // The bone before the operation moved it: the contact is defined there.
  vtkSmartPointer<vtkPointSet> undeformed = UndeformedBone(bone, undeformedPoints);
  vtkNew<vtkStaticCellLocator> locator;
  locator->SetDataSet(undeformed);
  locator->BuildLocator();
  vtkNew<vtkGenericCell> cell;
  std::vector<double> weights(64);
  ContactMap map;
  map.weightStart.push_back(0);
  for (vtkIdType node : tissueBoundary) {
    double x[3], closest[3], dist2, pcoords[3];
    vtkIdType cellId;
    int subId, inside;
    tissue->GetPoint(node, x);
    if (!locator->FindClosestPointWithinRadius(x, contactDistance, closest, cell, cellId, subId,
                                               dist2, inside))
      continue;
    // The locator uses `cell` as scratch space: fetch the closest cell itself.
    undeformed->GetCell(cellId, cell);
    const vtkIdType n = cell->GetNumberOfPoints();
    if (static_cast<size_t>(n) > weights.size())
      weights.resize(n);
    double evalClosest[3], evalDist2;
    cell->EvaluatePosition(closest, evalClosest, subId, pcoords, evalDist2, weights.data());
    double mask = 1.0;
    if (roiMask) {
      mask = 0.0;
      for (vtkIdType k = 0; k < n; ++k)
        mask += weights[k] * roiMask->GetComponent(cell->GetPointId(k), 0);
    }
    map.tiedNodes.push_back(static_cast<int>(node));
    map.movable.push_back(mask > 1e-12 ? 1 : 0);
    vtkIdType heaviest = 0;
    for (vtkIdType k = 1; k < n; ++k)
      if (weights[k] > weights[heaviest])
        heaviest = k;
    map.nearestBonePoint.push_back(cell->GetPointId(heaviest));
    double normal[3] = {0.0, 0.0, 0.0};
    vtkPolygon::ComputeNormal(cell->GetPoints(), normal);
    map.normals.insert(map.normals.end(), normal, normal + 3);
    for (vtkIdType k = 0; k < n; ++k) {
      map.bonePointIds.push_back(cell->GetPointId(k));
      map.weights.push_back(weights[k]);
    }
    map.weightStart.push_back(static_cast<vtkIdType>(map.weights.size()));
  }
  MarkReleased(tissue, undeformed, bone, releaseDistance, map);
  return map;
}

} // namespace

Status ContactCache::build(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                           vtkPointSet* bone, const std::vector<double>& undeformed,
                           double contactDistance, double releaseDistance) {
  if (undeformed.size() != static_cast<size_t>(3 * bone->GetNumberOfPoints()))
    return Status::Error("the undeformed bone does not match the bone's points");
  map_ =
      BuildContactMap(tissue, tissueBoundary, bone, undeformed, contactDistance, releaseDistance);
  return Status::Ok();
}

ContactModelChoice ResolveContactModel(ContactModelChoice chosen, bool boneHasSliding) {
  if (chosen != ContactModelChoice::Auto)
    return chosen;
  return boneHasSliding ? ContactModelChoice::ByArray : ContactModelChoice::Tied;
}

const char* ContactModelName(ContactModelChoice model) {
  switch (model) {
  case ContactModelChoice::Tied:
    return "Tied";
  case ContactModelChoice::Sliding:
    return "Sliding";
  case ContactModelChoice::ByArray:
    return "ByArray";
  case ContactModelChoice::Auto:
    break;
  }
  return "Auto";
}

NodeSets MakeNodeSets(const ContactMap& map, const std::vector<vtkIdType>& tissueBoundary,
                      ContactModelChoice model, vtkDataArray* slidingFlags,
                      const std::vector<int>& segmentOfBonePoint) {
  NodeSets sets;
  for (size_t t = 0; t < map.tiedNodes.size(); ++t) {
    if (map.released[t])
      continue;
    const int node = map.tiedNodes[t];
    const vtkIdType bonePoint = map.nearestBonePoint[t];
    sets.constrained.push_back(node);
    if (map.movable[t]) {
      sets.movable.push_back(node);
      if (!segmentOfBonePoint.empty())
        sets.movableSegment.push_back(segmentOfBonePoint[bonePoint]);
    }
    const bool sliding = model == ContactModelChoice::Sliding ||
                         (model == ContactModelChoice::ByArray && slidingFlags &&
                          slidingFlags->GetComponent(bonePoint, 0) > 0.0);
    const Eigen::Vector3d normal(map.normals[3 * t], map.normals[3 * t + 1],
                                 map.normals[3 * t + 2]);
    if (sliding && std::abs(normal.norm() - 1.0) < 1e-6) {
      sets.sliding.push_back(node);
      sets.slidingNormal.push_back(normal);
    }
  }
  for (vtkIdType node : tissueBoundary)
    sets.kept.push_back(static_cast<int>(node));
  return sets;
}

size_t ReleasedCount(const ContactMap& map) {
  return static_cast<size_t>(std::count(map.released.begin(), map.released.end(), 1));
}

RowVectors3d MovableDisplacements(const ContactMap& map, vtkDataArray* boneDisplacement) {
  Eigen::Index movable = 0;
  for (size_t t = 0; t < map.tiedNodes.size(); ++t)
    movable += map.movable[t] && !map.released[t] ? 1 : 0;
  RowVectors3d out = RowVectors3d::Zero(movable, 3);
  for (size_t t = 0, row = 0; t < map.tiedNodes.size(); ++t) {
    if (!map.movable[t] || map.released[t])
      continue;
    for (vtkIdType k = map.weightStart[t]; k < map.weightStart[t + 1]; ++k) {
      double d[3];
      boneDisplacement->GetTuple(map.bonePointIds[k], d);
      for (int c = 0; c < 3; ++c)
        out(static_cast<Eigen::Index>(row), c) += map.weights[k] * d[c];
    }
    ++row;
  }
  return out;
}

} // namespace fem_filter
} // namespace faceplan
