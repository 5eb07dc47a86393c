#include "vtkROIExtract.h"

#include "FacePlanVTKConvert.h"
#include "ROIExtract/ROIExtract.h"

#include <vtkImplicitFunction.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkUnsignedCharArray.h>

vtkStandardNewMacro(vtkROIExtract);
vtkCxxSetObjectMacro(vtkROIExtract, Region, vtkImplicitFunction);

vtkROIExtract::vtkROIExtract() = default;

vtkROIExtract::~vtkROIExtract() { this->SetRegion(nullptr); }

void vtkROIExtract::SetNumberOfPointIds(vtkIdType n) {
  if (n < 0) n = 0;
  if (static_cast<vtkIdType>(this->PointIds.size()) != n) {
    this->PointIds.resize(static_cast<std::size_t>(n), 0);
    this->Modified();
  }
}

void vtkROIExtract::SetPointId(vtkIdType index, vtkIdType pointId) {
  if (index < 0) return;
  if (index >= static_cast<vtkIdType>(this->PointIds.size()))
    this->PointIds.resize(static_cast<std::size_t>(index + 1), 0);
  if (this->PointIds[index] != pointId) {
    this->PointIds[index] = pointId;
    this->Modified();
  }
}

void vtkROIExtract::AddPointId(vtkIdType pointId) {
  this->PointIds.push_back(pointId);
  this->Modified();
}

void vtkROIExtract::RemoveAllPointIds() {
  if (!this->PointIds.empty()) {
    this->PointIds.clear();
    this->Modified();
  }
}

vtkIdType vtkROIExtract::GetPointId(vtkIdType index) const {
  return index >= 0 && index < static_cast<vtkIdType>(this->PointIds.size()) ? this->PointIds[index] : -1;
}

vtkMTimeType vtkROIExtract::GetMTime() {
  vtkMTimeType t = this->Superclass::GetMTime();
  if (this->Region) t = std::max(t, this->Region->GetMTime());
  return t;
}

int vtkROIExtract::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                               vtkInformationVector* outputVector) {
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  vtkPointSet* output = vtkPointSet::GetData(outputVector, 0);
  if (!input || !output) {
    vtkErrorMacro(<< "ROI Extract needs a vtkPointSet input");
    return 1;
  }
  output->Initialize();
  const vtkIdType n = input->GetNumberOfPoints();
  if (n == 0) {
    vtkErrorMacro(<< "ROI Extract: the input has no points");
    return 1;
  }
  if (this->PointIds.empty() && !this->Region) {
    vtkErrorMacro(<< "ROI Extract: no ROI given (set Region or PointIds)");
    return 1;
  }

  faceplan::SurfaceMesh mesh;
  std::string why;
  if (!faceplan::vtkconvert::ToSurfaceMesh(input, faceplan::vtkconvert::CellPolicy::EdgesOfAnyCell, mesh, why)) {
    vtkErrorMacro(<< "ROI Extract: " << why);
    return 1;
  }

  std::vector<std::uint8_t> selected(static_cast<std::size_t>(n), 0);
  if (!this->PointIds.empty()) {
    for (vtkIdType id : this->PointIds) {
      if (id < 0 || id >= n) {
        vtkErrorMacro(<< "ROI Extract: point id " << id << " out of range [0, " << n << ")");
        return 1;
      }
      selected[static_cast<std::size_t>(id)] = 1;
    }
  } else {
    for (vtkIdType i = 0; i < n; ++i) {
      double p[3];
      input->GetPoint(i, p);
      selected[static_cast<std::size_t>(i)] = this->Region->FunctionValue(p) < 0.0 ? 1 : 0;
    }
  }
  if (this->InsideOut)
    for (auto& s : selected) s = s ? 0 : 1;

  faceplan::ROIResult roi;
  const faceplan::Status status = faceplan::ComputeROI(mesh, selected, roi);
  if (!status) {
    vtkErrorMacro(<< "ROI Extract: " << status.message);
    return 1;
  }

  output->ShallowCopy(input);
  vtkNew<vtkUnsignedCharArray> mask, boundary;
  mask->SetName("ROIMask");
  boundary->SetName("ROIBoundary");
  mask->SetNumberOfTuples(n);
  boundary->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i) {
    mask->SetValue(i, roi.mask[static_cast<std::size_t>(i)]);
    boundary->SetValue(i, roi.boundary[static_cast<std::size_t>(i)]);
  }
  output->GetPointData()->RemoveArray("ROIMask");
  output->GetPointData()->RemoveArray("ROIBoundary");
  output->GetPointData()->AddArray(mask);
  output->GetPointData()->AddArray(boundary);
  if (roi.numROI == 0) vtkWarningMacro(<< "ROI Extract: the ROI is empty");
  return 1;
}

void vtkROIExtract::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Region: " << this->Region << "\n";
  os << indent << "PointIds: " << this->PointIds.size() << " ids\n";
  os << indent << "InsideOut: " << this->InsideOut << "\n";
}
