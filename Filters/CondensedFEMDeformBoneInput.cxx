// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformBoneInput.h"

#include "CondensedFEMDeformValidate.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPolyData.h"

#include <Eigen/Core>

#include <cmath>

namespace faceplan {
namespace fem_filter {

DataStamp BoneInput::StructureStampOf(vtkPointSet* bone) {
  DataStamp stamp;
  stamp.object = nullptr; // an edit may hand over a new bone object with the same cells
  stamp.times.push_back(static_cast<vtkMTimeType>(bone->GetNumberOfPoints()));
  AddCellsToStamp(stamp, bone);
  for (const char* name : kStructureArrays)
    AddToStamp(stamp, bone->GetPointData()->GetArray(name));
  return stamp;
}

void BoneInput::StructureSignature(vtkPointSet* bone, std::vector<unsigned char>& out) {
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

const std::vector<unsigned char>& BoneInput::signature(vtkPointSet* bone) {
  if (!haveSignature_) {
    StructureSignature(bone, signature_);
    haveSignature_ = true;
  }
  return signature_;
}

bool BoneInput::sameUndeformed() const {
  if (undeformed_.size() != contactUndeformed_.size())
    return false;
  if (undeformed_.empty())
    return true;
  // Equal up to 1e-9 of the undeformed bone's diagonal, taken from the values just validated: the
  // bone's own bounds would be computed afresh on every edit (its points are new each time).
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> points(
      undeformed_.data(), static_cast<Eigen::Index>(undeformed_.size() / 3), 3);
  const double tolerance =
      1e-9 * (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  for (size_t k = 0; k < undeformed_.size(); ++k)
    if (!(std::abs(undeformed_[k] - contactUndeformed_[k]) <= tolerance))
      return false;
  return true;
}

Status BoneInput::update(vtkPointSet* bone, unsigned long tissueGeneration, double contactDistance,
                         double releaseDistance) {
  structureChanged_ = contactChanged_ = true;
  haveSignature_ = false;
  if (!bone)
    return ValidateBone(bone, undeformed_);
  stamp_ = StructureStampOf(bone);
  // Validation: in full for a new structure, else only the values an edit changes.
  const bool sameStructure =
      validated_ && (stamp_ == validatedStamp_ || signature(bone) == validatedSignature_);
  const Status status =
      sameStructure ? ValidateBoneValues(bone, undeformed_) : ValidateBone(bone, undeformed_);
  if (!status) {
    validated_ = validated_ && sameStructure;
    return status;
  }
  structureChanged_ = !sameStructure;
  if (!sameStructure)
    validatedSignature_ = signature(bone);
  validatedStamp_ = stamp_;
  validated_ = true;

  // The contact: same tissue, distances, structure and undeformed points as when it was built.
  tissue_ = tissueGeneration;
  contactDistance_ = contactDistance;
  releaseDistance_ = releaseDistance;
  contactChanged_ =
      !(haveContact_ && tissueGeneration == contactTissue_ &&
        contactDistance == contactDistanceBuilt_ && releaseDistance == releaseDistanceBuilt_ &&
        (stamp_ == contactStamp_ || signature(bone) == contactSignature_) && sameUndeformed());
  if (contactChanged_)
    signature(bone); // for contactBuilt
  return Status::Ok();
}

void BoneInput::contactBuilt() {
  contactStamp_ = stamp_;
  contactSignature_ = signature_;
  contactUndeformed_ = undeformed_;
  contactTissue_ = tissue_;
  contactDistanceBuilt_ = contactDistance_;
  releaseDistanceBuilt_ = releaseDistance_;
  haveContact_ = true;
  contactChanged_ = false;
}

} // namespace fem_filter
} // namespace faceplan
