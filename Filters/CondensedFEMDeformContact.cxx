#include "CondensedFEMDeformContact.h"

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

// The bone before the operation moved it: the contact is defined there.
vtkSmartPointer<vtkPointSet> Undeformed(vtkPointSet* bone, vtkDataArray* displacement) {
  vtkSmartPointer<vtkPointSet> undeformed;
  undeformed.TakeReference(vtkPointSet::SafeDownCast(bone->NewInstance()));
  undeformed->CopyStructure(bone);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(bone->GetNumberOfPoints());
  for (vtkIdType i = 0; i < bone->GetNumberOfPoints(); ++i) {
    double p[3], d[3];
    bone->GetPoint(i, p);
    displacement->GetTuple(i, d);
    points->SetPoint(i, p[0] - d[0], p[1] - d[1], p[2] - d[2]);
  }
  undeformed->SetPoints(points);
  return undeformed;
}

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
                           vtkPointSet* bone, double contactDistance, double releaseDistance) {
  vtkDataArray* displacement = bone->GetPointData()->GetArray("Displacement");
  vtkDataArray* roiMask = bone->GetPointData()->GetArray("ROIMask");
  vtkSmartPointer<vtkPointSet> undeformed = Undeformed(bone, displacement);
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

ContactCache::Key ContactCache::MakeKey(vtkPointSet* tissue,
                                        const std::vector<vtkIdType>& tissueBoundary,
                                        vtkPointSet* bone, double contactDistance,
                                        double releaseDistance) {
  Key key;
  vtkDataArray* displacement = bone->GetPointData()->GetArray("Displacement");
  key.undeformedBone.resize(3 * bone->GetNumberOfPoints());
  for (vtkIdType i = 0; i < bone->GetNumberOfPoints(); ++i) {
    double p[3], d[3];
    bone->GetPoint(i, p);
    displacement->GetTuple(i, d);
    for (int c = 0; c < 3; ++c)
      key.undeformedBone[3 * i + c] = p[c] - d[c];
  }
  if (vtkDataArray* mask = bone->GetPointData()->GetArray("ROIMask"))
    for (vtkIdType i = 0; i < mask->GetNumberOfTuples(); ++i)
      key.mask.push_back(mask->GetComponent(i, 0));
  if (vtkDataArray* ids = bone->GetPointData()->GetArray("SegmentId"))
    for (vtkIdType i = 0; i < ids->GetNumberOfTuples(); ++i)
      key.segmentIds.push_back(ids->GetComponent(i, 0));
  if (vtkDataArray* flags = bone->GetPointData()->GetArray("Released"))
    for (vtkIdType i = 0; i < flags->GetNumberOfTuples(); ++i)
      key.releasedFlags.push_back(flags->GetComponent(i, 0));
  key.hasReleasedFlags = bone->GetPointData()->GetArray("Released") != nullptr;
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < bone->GetNumberOfCells(); ++c) {
    bone->GetCellPoints(c, ids);
    key.boneCells.push_back(bone->GetCellType(c));
    key.boneCells.push_back(ids->GetNumberOfIds());
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
      key.boneCells.push_back(ids->GetId(k));
  }
  key.tissuePoints.resize(3 * tissue->GetNumberOfPoints());
  for (vtkIdType i = 0; i < tissue->GetNumberOfPoints(); ++i)
    tissue->GetPoint(i, &key.tissuePoints[3 * i]);
  key.tissueBoundary = tissueBoundary;
  key.distance = contactDistance;
  key.release = releaseDistance;
  return key;
}

Status ContactCache::update(vtkPointSet* tissue, const std::vector<vtkIdType>& tissueBoundary,
                            vtkPointSet* bone, double contactDistance, double releaseDistance) {
  Key key = MakeKey(tissue, tissueBoundary, bone, contactDistance, releaseDistance);
  // The undeformed bone is bone points minus Displacement: an edit changes both by the same amount,
  // so compare with a tolerance relative to the bone's size instead of bit for bit.
  bool same = valid_ && key.undeformedBone.size() == key_.undeformedBone.size() &&
              key.mask == key_.mask && key.segmentIds == key_.segmentIds &&
              key.releasedFlags == key_.releasedFlags &&
              key.hasReleasedFlags == key_.hasReleasedFlags && key.release == key_.release &&
              key.boneCells == key_.boneCells && key.tissuePoints == key_.tissuePoints &&
              key.tissueBoundary == key_.tissueBoundary && key.distance == key_.distance;
  if (same) {
    double bounds[6];
    bone->GetBounds(bounds);
    const double tolerance = 1e-9 * std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
                                              (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
                                              (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
    for (size_t k = 0; same && k < key.undeformedBone.size(); ++k)
      same = std::abs(key.undeformedBone[k] - key_.undeformedBone[k]) <= tolerance;
  }
  if (same)
    return Status::Ok();
  valid_ = false;
  map_ = BuildContactMap(tissue, tissueBoundary, bone, contactDistance, releaseDistance);
  key_ = std::move(key);
  valid_ = true;
  return Status::Ok();
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
