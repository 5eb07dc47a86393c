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
  for (const char* name : kStructureArrays)
    AddToStamp(stamp, bone->GetPointData()->GetArray(name));
  return stamp;
}

void BoneCache::StructureSignature(vtkPointSet* bone, std::vector<unsigned char>& out) {
  out.clear();
  auto appendValue = [&](long long value) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
    out.insert(out.end(), bytes, bytes + sizeof(value));
  };
  // The raw bytes of an array with its type and shape: equal bytes are equal values, NaN included.
  auto appendArray = [&](vtkDataArray* array) {
    appendValue(array ? array->GetDataType() : -1); // absent differs from empty
    if (!array)
      return;
    appendValue(array->GetNumberOfComponents());
    appendValue(array->GetNumberOfTuples());
    const auto* bytes = static_cast<const unsigned char*>(array->GetVoidPointer(0));
    if (bytes)
      out.insert(out.end(), bytes,
                 bytes +
                     array->GetNumberOfValues() * static_cast<vtkIdType>(array->GetDataTypeSize()));
  };
  appendValue(bone->GetNumberOfPoints());
  if (auto* poly = vtkPolyData::SafeDownCast(bone)) {
    for (vtkCellArray* cells :
         {poly->GetVerts(), poly->GetLines(), poly->GetPolys(), poly->GetStrips()}) {
      appendArray(cells ? cells->GetOffsetsArray() : nullptr);
      appendArray(cells ? cells->GetConnectivityArray() : nullptr);
    }
  } else {
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = 0; c < bone->GetNumberOfCells(); ++c) {
      bone->GetCellPoints(c, ids);
      appendValue(bone->GetCellType(c));
      appendValue(ids->GetNumberOfIds());
      for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
        appendValue(ids->GetId(k));
    }
  }
  for (const char* name : kStructureArrays)
    appendArray(bone->GetPointData()->GetArray(name));
}

const std::vector<unsigned char>& BoneCache::signatureOf(vtkPointSet* bone,
                                                         const DataStamp& stamp) {
  if (!haveSignature_ || stamp != signatureStamp_) {
    StructureSignature(bone, signature_);
    signatureStamp_ = stamp;
    haveSignature_ = true;
  }
  return signature_;
}

Status BoneCache::validate(vtkPointSet* bone) {
  if (!bone)
    return ValidateBone(bone);
  DataStamp structure = StructureStampOf(bone);
  // An edit through Osteotomy, Append Geometry or several Bone connections hands over new arrays
  // with the same cells and labels: their bytes decide, not their stamps.
  if (validated_ && structure != validatedStructure_ &&
      signatureOf(bone, structure) == validatedSignature_)
    validatedStructure_ = structure;
  if (validated_ && structure == validatedStructure_)
    return ValidateBoneValues(bone);
  validated_ = false;
  const Status status = ValidateBone(bone);
  if (status) {
    validatedSignature_ = signatureOf(bone, structure);
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

bool BoneCache::contactStillValid(vtkPointSet* bone, unsigned long tissueGeneration,
                                  double contactDistance) {
  bool same =
      haveContact_ && tissueGeneration == contactTissue_ && contactDistance == contactDistance_;
  if (same) {
    const DataStamp structure = StructureStampOf(bone);
    same = structure == contactStamp_ || signatureOf(bone, structure) == contactSignature_;
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
  contactStamp_ = StructureStampOf(bone);
  contactSignature_ = signatureOf(bone, contactStamp_);
  contactTissue_ = tissueGeneration;
  contactDistance_ = contactDistance;
  UndeformedPoints(bone, contactUndeformed_);
  haveContact_ = true;
}

} // namespace fem_filter
} // namespace faceplan
