// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformBone.h"

#include "vtkAppendFilter.h"
#include "vtkConnectivityFilter.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace faceplan {
namespace fem_filter {

namespace {

int SegmentCountOf(vtkPointSet* bone) {
  vtkDataArray* transforms = bone->GetFieldData()->GetArray("SegmentTransform");
  const vtkIdType values = transforms ? transforms->GetNumberOfValues() : 0;
  int fromIds = 0;
  if (vtkDataArray* ids = bone->GetPointData()->GetArray("SegmentId"))
    for (vtkIdType i = 0; i < ids->GetNumberOfTuples(); ++i)
      fromIds = std::max(fromIds, static_cast<int>(std::lround(ids->GetComponent(i, 0))));
  return std::max(fromIds, static_cast<int>(values / 12));
}

// A point array of `bone` as a fresh array of the given type, or `fill` everywhere when absent;
// SegmentId values above 0 are offset by `offset`.
template <class Array>
vtkSmartPointer<Array> PointArrayOrFill(vtkPointSet* bone, const char* name, double fill,
                                        int offset = 0) {
  vtkNew<Array> out;
  out->SetName(name);
  out->SetNumberOfTuples(bone->GetNumberOfPoints());
  vtkDataArray* in = bone->GetPointData()->GetArray(name);
  for (vtkIdType i = 0; i < bone->GetNumberOfPoints(); ++i) {
    double v = in ? in->GetComponent(i, 0) : fill;
    if (offset && v > 0.5)
      v += offset;
    out->SetValue(i, static_cast<typename Array::ValueType>(v));
  }
  return vtkSmartPointer<Array>(out.GetPointer());
}

// The connected piece of the bone (vtkConnectivityFilter's region) of each point; -1 for points
// of no cell.
std::vector<vtkIdType> PieceOfPoint(vtkPointSet* bone) {
  vtkSmartPointer<vtkPointSet> copy;
  copy.TakeReference(bone->NewInstance());
  copy->CopyStructure(bone);
  vtkNew<vtkIdTypeArray> index;
  index->SetName("BonePointIndex");
  index->SetNumberOfTuples(bone->GetNumberOfPoints());
  for (vtkIdType i = 0; i < bone->GetNumberOfPoints(); ++i)
    index->SetValue(i, i);
  copy->GetPointData()->AddArray(index);
  vtkNew<vtkConnectivityFilter> connectivity;
  connectivity->SetInputData(copy);
  connectivity->SetExtractionModeToAllRegions();
  connectivity->ColorRegionsOn();
  connectivity->Update();
  auto* out = vtkPointSet::SafeDownCast(connectivity->GetOutputDataObject(0));
  std::vector<vtkIdType> piece(bone->GetNumberOfPoints(), -1);
  vtkDataArray* ids = out ? out->GetPointData()->GetArray("BonePointIndex") : nullptr;
  vtkDataArray* regions = out ? out->GetPointData()->GetArray("RegionId") : nullptr;
  for (vtkIdType i = 0; ids && regions && i < out->GetNumberOfPoints(); ++i)
    piece[static_cast<vtkIdType>(ids->GetComponent(i, 0))] =
        static_cast<vtkIdType>(regions->GetComponent(i, 0));
  return piece;
}

// When a segment's Displacement does not follow its transform: whether the segment lies on
// several separate pieces of the bone of which some follow the transform and some do not. That is
// what appending several Osteotomy outputs into one data set (Append Geometry) gives: each output
// numbers its segment 1, and the field data keeps one SegmentTransform. The note says so, or is
// empty when the segment is simply not rigid.
std::string AppendedSegmentsNote(vtkPointSet* bone, const RowVectors3d& undeformed,
                                 const RowVectors3d& displacement, const NodeSets& sets,
                                 const std::vector<SegmentTransform>& transforms) {
  const std::vector<vtkIdType> piece = PieceOfPoint(bone);
  // (segment, piece) -> the movable entries on it
  std::map<std::pair<int, vtkIdType>, std::vector<size_t>> groups;
  for (size_t k = 0; k < sets.movable.size(); ++k)
    groups[{sets.movableSegment[k], piece[sets.movable[k]]}].push_back(k);
  std::map<int, std::pair<int, int>> followingAndNot; // segment -> pieces that follow, that don't
  for (const auto& [key, entries] : groups) {
    NodeSets one;
    RowVectors3d u(static_cast<Eigen::Index>(entries.size()), 3);
    for (size_t e = 0; e < entries.size(); ++e) {
      one.movable.push_back(sets.movable[entries[e]]);
      one.movableSegment.push_back(sets.movableSegment[entries[e]]);
      u.row(static_cast<Eigen::Index>(e)) = displacement.row(sets.movable[entries[e]]);
    }
    const bool follows =
        static_cast<bool>(CheckSegmentDisplacements(undeformed, one, transforms, u));
    auto& count = followingAndNot[key.first];
    (follows ? count.first : count.second) += 1;
  }
  for (const auto& [segment, count] : followingAndNot)
    if (count.first > 0 && count.second > 0) {
      std::ostringstream note;
      note << "SegmentId " << segment << " lies on " << count.first + count.second
           << " separate pieces of the bone that move differently, with one SegmentTransform: "
              "several Osteotomy outputs appended into one data set (Append Geometry keeps one "
              "transform and numbers every segment 1). The general path is exact for it; connect "
              "each Osteotomy to the Bone port instead (several connections) for the rigid path";
      return note.str();
    }
  return std::string();
}

} // namespace

vtkSmartPointer<vtkPointSet> WithZeroDisplacement(vtkPointSet* bone) {
  vtkSmartPointer<vtkPointSet> fixed;
  fixed.TakeReference(bone->NewInstance());
  fixed->ShallowCopy(bone);
  vtkNew<vtkDoubleArray> zero;
  zero->SetName("Displacement");
  zero->SetNumberOfComponents(3);
  zero->SetNumberOfTuples(bone->GetNumberOfPoints());
  zero->Fill(0.0);
  fixed->GetPointData()->AddArray(zero);
  return fixed;
}

vtkSmartPointer<vtkPointSet> MergeBones(const std::vector<vtkPointSet*>& bones) {
  if (bones.size() == 1)
    return vtkSmartPointer<vtkPointSet>(bones[0]);
  bool anySegments = false, anySliding = false, anyReleased = false;
  for (vtkPointSet* bone : bones) {
    anySegments |= bone->GetPointData()->GetArray("SegmentId") != nullptr;
    anySliding |= bone->GetPointData()->GetArray("Sliding") != nullptr;
    anyReleased |= bone->GetPointData()->GetArray("Released") != nullptr;
  }
  vtkNew<vtkAppendFilter> append;
  append->MergePointsOff();
  vtkNew<vtkDoubleArray> transforms;
  transforms->SetName("SegmentTransform");
  int offset = 0;
  for (vtkPointSet* bone : bones) {
    vtkSmartPointer<vtkPointSet> copy;
    copy.TakeReference(bone->NewInstance());
    copy->CopyStructure(bone);
    vtkPointData* pd = copy->GetPointData();
    vtkNew<vtkDoubleArray> displacement;
    displacement->DeepCopy(bone->GetPointData()->GetArray("Displacement"));
    displacement->SetName("Displacement");
    pd->AddArray(displacement);
    pd->AddArray(PointArrayOrFill<vtkUnsignedCharArray>(bone, "ROIMask", 1.0));
    if (anySegments)
      pd->AddArray(PointArrayOrFill<vtkIntArray>(bone, "SegmentId", 0.0, offset));
    if (anySliding)
      pd->AddArray(PointArrayOrFill<vtkUnsignedCharArray>(bone, "Sliding", 0.0));
    if (anyReleased)
      pd->AddArray(PointArrayOrFill<vtkUnsignedCharArray>(bone, "Released", 0.0));
    const int segments = SegmentCountOf(bone);
    vtkDataArray* own = bone->GetFieldData()->GetArray("SegmentTransform");
    for (int v = 0; v < 12 * segments; ++v)
      transforms->InsertNextValue(own && v < own->GetNumberOfValues()
                                      ? own->GetComponent(v / own->GetNumberOfComponents(),
                                                          v % own->GetNumberOfComponents())
                                      : std::nan(""));
    offset += segments;
    append->AddInputData(copy);
  }
  append->Update();
  vtkSmartPointer<vtkPointSet> merged = append->GetOutput();
  if (anySegments)
    merged->GetFieldData()->AddArray(transforms);
  return merged;
}

BoneSegments ReadBoneSegments(vtkPointSet* bone, const std::vector<double>& undeformedPoints) {
  BoneSegments out;
  vtkDataArray* ids = bone->GetPointData()->GetArray("SegmentId");
  vtkDataArray* values = bone->GetFieldData()->GetArray("SegmentTransform");
  if (!ids || !values) {
    out.whyNot = "the bone has no SegmentId point array and SegmentTransform field data";
    return out;
  }
  const vtkIdType n = bone->GetNumberOfPoints();
  const int components = values->GetNumberOfComponents();
  const vtkIdType count = values->GetNumberOfValues() / 12;
  if (values->GetNumberOfValues() % 12 != 0 || ids->GetNumberOfTuples() != n) {
    out.whyNot = "SegmentTransform must hold 12 values per segment and SegmentId one per point";
    return out;
  }
  // Segments with a finite transform, renumbered 1..s.
  std::vector<int> coreSegment(count + 1, 0);
  for (vtkIdType s = 0; s < count; ++s) {
    SegmentTransform t;
    for (int v = 0; v < 12; ++v) {
      const vtkIdType index = 12 * s + v;
      t(v / 4, v % 4) = values->GetComponent(index / components, index % components);
    }
    if (!t.allFinite())
      continue;
    out.transforms.push_back(t);
    coreSegment[s + 1] = static_cast<int>(out.transforms.size());
  }
  out.segmentOfPoint.assign(n, 0);
  NodeSets sets;
  RowVectors3d undeformed(n, 3);
  RowVectors3d displacement(n, 3);
  vtkDataArray* d = bone->GetPointData()->GetArray("Displacement");
  if (undeformedPoints.size() != static_cast<size_t>(3 * n)) {
    out.whyNot = "the undeformed bone does not match the bone's points";
    return out;
  }
  // Osteotomy's Displacement is a double array: read in place, without a virtual call per point.
  auto* moves = vtkDoubleArray::FastDownCast(d);
  const double* raw = moves && moves->GetNumberOfComponents() == 3 ? moves->GetPointer(0) : nullptr;
  for (vtkIdType i = 0; i < n; ++i) {
    double u[3];
    if (raw)
      std::copy(raw + 3 * i, raw + 3 * i + 3, u);
    else
      d->GetTuple(i, u);
    for (int c = 0; c < 3; ++c) {
      undeformed(i, c) = undeformedPoints[3 * i + c];
      displacement(i, c) = u[c];
    }
    const long id = std::lround(ids->GetComponent(i, 0));
    if (id > 0 && id <= count && coreSegment[id] > 0) {
      out.segmentOfPoint[i] = coreSegment[id];
      sets.movable.push_back(static_cast<int>(i));
      sets.movableSegment.push_back(coreSegment[id]);
    }
  }
  if (out.transforms.empty() || sets.movable.empty()) {
    out.whyNot = "no bone point lies on a segment with a finite SegmentTransform";
    return out;
  }
  RowVectors3d segmentDisplacement(static_cast<Eigen::Index>(sets.movable.size()), 3);
  for (size_t k = 0; k < sets.movable.size(); ++k)
    segmentDisplacement.row(static_cast<Eigen::Index>(k)) = displacement.row(sets.movable[k]);
  const Status check =
      CheckSegmentDisplacements(undeformed, sets, out.transforms, segmentDisplacement);
  if (!check) {
    out.whyNot = AppendedSegmentsNote(bone, undeformed, displacement, sets, out.transforms);
    if (out.whyNot.empty())
      out.whyNot =
          "the bone's Displacement does not follow SegmentTransform (" + check.message + ")";
    return out;
  }
  out.usable = true;
  return out;
}

} // namespace fem_filter
} // namespace faceplan
