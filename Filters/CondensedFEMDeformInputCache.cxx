#include "CondensedFEMDeformInputCache.h"

#include "CondensedFEMDeformValidate.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <cmath>

namespace faceplan {
namespace fem_filter {

namespace {

template <class Matrix> bool SameMatrix(const Matrix& a, const Matrix& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
}

bool SameMaterials(const Materials& a, const Materials& b) {
  return SameMatrix(a.youngsModulus, b.youngsModulus) &&
         SameMatrix(a.poissonRatio, b.poissonRatio) && SameMatrix(a.density, b.density);
}

} // namespace

Status TissueCache::update(vtkUnstructuredGrid* tissue, const Settings& settings) {
  DataStamp stamp = StampOf(tissue);
  const MaterialSettings materialSettings{settings.youngsModulus, settings.poissonRatio,
                                          settings.density, settings.lengthUnit,
                                          settings.useCellMaterials};
  if (valid_ && stamp == stamp_ && materialSettings == materialSettings_)
    return Status::Ok();

  Status status = ValidateTissue(tissue, settings);
  TetMesh mesh;
  Materials materials;
  if (status) {
    ToTetMesh(tissue, mesh);
    status = ToMaterials(tissue, settings, materials);
  }
  if (!status) {
    valid_ = false;
    return status;
  }
  // A new stamp with the content of the last one (an upstream filter re-executed, a copied data
  // set) keeps the generation, and with it the contact and the precompute.
  const bool sameMesh = valid_ && SameMatrix(mesh.points, mesh_.points) &&
                        SameMatrix(mesh.tets, mesh_.tets) && !boundary_.nodes.empty();
  const bool sameMaterials = valid_ && SameMaterials(materials, materials_);
  if (!sameMesh) {
    boundary_ = ExtractBoundary(tissue);
    mesh_ = std::move(mesh);
  }
  if (!sameMesh || !sameMaterials) {
    materials_ = std::move(materials);
    ++generation_;
  }
  stamp_ = std::move(stamp);
  materialSettings_ = materialSettings;
  valid_ = true;
  return Status::Ok();
}

DataStamp BoneCache::StructureStampOf(vtkPointSet* bone) {
  DataStamp stamp;
  stamp.object = nullptr; // an edit may hand over a new bone object with the same cells
  stamp.times.push_back(static_cast<vtkMTimeType>(bone->GetNumberOfPoints()));
  AddCellsToStamp(stamp, bone);
  AddToStamp(stamp, bone->GetPointData()->GetArray("ROIMask"));
  return stamp;
}

Status BoneCache::validate(vtkPointSet* bone) {
  if (!bone)
    return ValidateBone(bone);
  DataStamp structure = StructureStampOf(bone);
  if (validated_ && structure == validatedStructure_)
    return ValidateBoneValues(bone);
  validated_ = false;
  const Status status = ValidateBone(bone);
  if (status) {
    validatedStructure_ = std::move(structure);
    validated_ = true;
  }
  return status;
}

void BoneCache::UndeformedPoints(vtkPointSet* bone, std::vector<double>& points) {
  const vtkIdType n = bone->GetNumberOfPoints();
  vtkDataArray* displacement = bone->GetPointData()->GetArray("Displacement");
  points.resize(static_cast<size_t>(3 * n));
  auto* p = vtkDoubleArray::FastDownCast(bone->GetPoints()->GetData());
  auto* d = vtkDoubleArray::FastDownCast(displacement);
  if (p && d) { // BezierCut's and Osteotomy's output: no per-value virtual calls
    const double* x = p->GetPointer(0);
    const double* u = d->GetPointer(0);
    for (vtkIdType k = 0; k < 3 * n; ++k)
      points[k] = x[k] - u[k];
    return;
  }
  for (vtkIdType i = 0; i < n; ++i) {
    double x[3], u[3];
    bone->GetPoint(i, x);
    displacement->GetTuple(i, u);
    for (int c = 0; c < 3; ++c)
      points[3 * i + c] = x[c] - u[c];
  }
}

DataStamp BoneCache::ContactStampOf(vtkPointSet* bone) {
  DataStamp stamp = StructureStampOf(bone);
  AddToStamp(stamp, bone->GetPointData()->GetArray("SegmentId"));
  return stamp;
}

void BoneCache::ContactStructure(vtkPointSet* bone, std::vector<vtkIdType>& cells,
                                 std::vector<double>& labels) {
  cells.clear();
  labels.clear();
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < bone->GetNumberOfCells(); ++c) {
    bone->GetCellPoints(c, ids);
    cells.push_back(bone->GetCellType(c));
    cells.push_back(ids->GetNumberOfIds());
    cells.insert(cells.end(), ids->begin(), ids->end());
  }
  for (const char* name : {"ROIMask", "SegmentId"}) {
    vtkDataArray* array = bone->GetPointData()->GetArray(name);
    labels.push_back(array ? array->GetNumberOfTuples() : -1); // absent differs from empty
    for (vtkIdType i = 0; array && i < array->GetNumberOfTuples(); ++i)
      labels.push_back(array->GetComponent(i, 0));
  }
}

bool BoneCache::contactStillValid(vtkPointSet* bone, unsigned long tissueGeneration,
                                  double contactDistance) {
  bool same =
      haveContact_ && tissueGeneration == contactTissue_ && contactDistance == contactDistance_;
  if (same && ContactStampOf(bone) != contactStamp_) {
    ContactStructure(bone, cellScratch_, labelScratch_);
    same = cellScratch_ == contactCells_ && labelScratch_ == contactLabels_;
  }
  if (same) {
    UndeformedPoints(bone, scratch_);
    // Points and Displacement move together in an edit: their difference may change by rounding
    // only, so the comparison has the same tolerance as the contact cache's own.
    double bounds[6];
    bone->GetBounds(bounds);
    const double tolerance = 1e-9 * std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
                                              (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
                                              (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
    same = scratch_.size() == contactUndeformed_.size();
    for (size_t k = 0; same && k < scratch_.size(); ++k)
      same = std::abs(scratch_[k] - contactUndeformed_[k]) <= tolerance;
  }
  if (!same)
    haveContact_ = false; // until contactBuilt confirms a new contact
  return same;
}

void BoneCache::contactBuilt(vtkPointSet* bone, unsigned long tissueGeneration,
                             double contactDistance) {
  contactStamp_ = ContactStampOf(bone);
  ContactStructure(bone, contactCells_, contactLabels_);
  contactTissue_ = tissueGeneration;
  contactDistance_ = contactDistance;
  UndeformedPoints(bone, contactUndeformed_);
  haveContact_ = true;
}

} // namespace fem_filter
} // namespace faceplan
