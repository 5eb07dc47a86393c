// SPDX-License-Identifier: BSD-3-Clause
#include "vtkROIExtract.h"

#include "FacePlanArrayRanges.h"
#include "FacePlanGather.h"
#include "FacePlanVTKConvert.h"
#include "ROIExtract/DefaultRegion.h"
#include "ROIExtract/ROIExtract.h"

#include <vtkAlgorithmOutput.h>
#include <vtkDataObject.h>
#include <vtkImplicitFunction.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkLinearTransform.h>
#include <vtkMatrix4x4.h>
#include <vtkMultiProcessController.h>
#include <vtkObjectFactory.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPolyData.h>
#include <vtkSphere.h>
#include <vtkUnsignedCharArray.h>

#include <cmath>
#include <sstream>

vtkStandardNewMacro(vtkROIExtract);

namespace {

// The Region's own parameters, checked before it is evaluated: a negative sphere radius or a
// mirrored box would silently select what their absolute values select.
std::string RegionProblem(vtkImplicitFunction* region) {
  std::ostringstream why;
  if (auto* sphere = vtkSphere::SafeDownCast(region)) {
    const double r = sphere->GetRadius();
    if (!(r > 0.0) || !std::isfinite(r)) {
      why << "the sphere Radius must be positive and finite (got " << r << ")";
      return why.str();
    }
  }
  if (auto* plane = vtkPlane::SafeDownCast(region)) {
    const double* n = plane->GetNormal();
    if (!(n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0))
      return "the plane Normal is zero (or NaN)";
  }
  if (auto* linear = vtkLinearTransform::SafeDownCast(region->GetTransform())) {
    // ParaView's Box places a unit box with this transform; its determinant is the inverse of
    // the product of the box's Lengths.
    const double det = linear->GetMatrix()->Determinant();
    if (!(det > 0.0) || !std::isfinite(det)) {
      why << "the box Length must be positive and finite on every axis (the region's transform "
          << (det < 0.0 ? "mirrors space" : "is singular or not finite") << ")";
      return why.str();
    }
  }
  return std::string();
}

} // namespace
vtkCxxSetObjectMacro(vtkROIExtract, Region, vtkImplicitFunction);

vtkROIExtract::vtkROIExtract() = default;

vtkROIExtract::~vtkROIExtract() {
  this->SetRegion(nullptr);
}

void vtkROIExtract::SetNumberOfPointIds(vtkIdType n) {
  if (n < 0)
    n = 0;
  if (static_cast<vtkIdType>(this->PointIds.size()) != n) {
    this->PointIds.resize(static_cast<std::size_t>(n), 0);
    this->Modified();
  }
}

void vtkROIExtract::SetPointId(vtkIdType index, vtkIdType pointId) {
  if (index < 0)
    return;
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
  return index >= 0 && index < static_cast<vtkIdType>(this->PointIds.size()) ? this->PointIds[index]
                                                                             : -1;
}

int vtkROIExtract::RequestDataObject(vtkInformation* request, vtkInformationVector** inputVector,
                                     vtkInformationVector* outputVector) {
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  if (input && !vtkPointSet::SafeDownCast(input)) {
    // An empty output of a valid type, so that RequestData reports the problem by name.
    vtkInformation* info = outputVector->GetInformationObject(0);
    if (!vtkPolyData::SafeDownCast(info->Get(vtkDataObject::DATA_OBJECT()))) {
      vtkNew<vtkPolyData> empty;
      info->Set(vtkDataObject::DATA_OBJECT(), empty);
    }
    return 1;
  }
  return this->Superclass::RequestDataObject(request, inputVector, outputVector);
}

// Asked while the proxy is created, before any Apply. Under MPI only rank 0 is asked and the
// upstream update is collective, so the sphere then comes from what rank 0 already holds.
double* vtkROIExtract::GetDefaultSphere() {
  this->DefaultSphere[0] = this->DefaultSphere[1] = this->DefaultSphere[2] = 0.0;
  this->DefaultSphere[3] = -1.0;
  vtkAlgorithmOutput* connection =
      this->GetNumberOfInputConnections(0) > 0 ? this->GetInputConnection(0, 0) : nullptr;
  vtkAlgorithm* upstream = connection ? connection->GetProducer() : nullptr;
  if (!upstream)
    return this->DefaultSphere;
  if (!faceplan::gather::DistributedController())
    upstream->Update(connection->GetIndex());
  auto* input = vtkPointSet::SafeDownCast(upstream->GetOutputDataObject(connection->GetIndex()));
  if (!input || input->GetNumberOfPoints() == 0)
    return this->DefaultSphere;
  faceplan::RowVectors3d points(input->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < input->GetNumberOfPoints(); ++i)
    input->GetPoint(i, &points(i, 0));
  Eigen::Vector3d centre;
  double radius = -1.0;
  if (faceplan::DefaultROISphere(points, centre, radius)) {
    for (int c = 0; c < 3; ++c)
      this->DefaultSphere[c] = centre[c];
    this->DefaultSphere[3] = radius;
  }
  return this->DefaultSphere;
}

vtkMTimeType vtkROIExtract::GetMTime() {
  vtkMTimeType t = this->Superclass::GetMTime();
  if (this->Region)
    t = std::max(t, this->Region->GetMTime());
  return t;
}

int vtkROIExtract::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                               vtkInformationVector* outputVector) {
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  vtkPointSet* output = vtkPointSet::GetData(outputVector, 0);
  if (!input || !output) {
    vtkDataObject* given = vtkDataObject::GetData(inputVector[0], 0);
    if (faceplan::gather::LogsErrors())
      vtkErrorMacro(
          << "ROI Extract needs a vtkPointSet input (a surface with points and cells), not "
          << (given ? given->GetClassName() : "nothing"));
    if (output)
      output->Initialize();
    return 1;
  }
  // Under MPI the ROI's connectivity needs the whole surface: gather it (FacePlanGather.h).
  if (vtkMultiProcessController* controller = faceplan::gather::DistributedController()) {
    faceplan::gather::RunOnWhole(
        controller, input, output,
        [this](vtkPointSet* in, vtkPointSet* out) { return this->Extract(in, out); });
  } else {
    this->Extract(input, output);
  }
  faceplan::CacheArrayRanges(output, {input});
  return 1;
}

bool vtkROIExtract::Extract(vtkPointSet* input, vtkPointSet* output) {
  output->Initialize();
  const vtkIdType n = input->GetNumberOfPoints();
  if (n == 0) {
    vtkErrorMacro(<< "ROI Extract: the input has no points");
    return false;
  }
  if (this->PointIds.empty() && !this->Region) {
    vtkErrorMacro(<< "ROI Extract: no ROI given (set Region or PointIds)");
    return false;
  }
  if (this->PointIds.empty()) {
    const std::string problem = RegionProblem(this->Region);
    if (!problem.empty()) {
      vtkErrorMacro(<< "ROI Extract: invalid Region: " << problem);
      return false;
    }
  }

  faceplan::SurfaceMesh mesh;
  std::string why;
  if (!faceplan::vtkconvert::ToSurfaceMesh(input, faceplan::vtkconvert::CellPolicy::EdgesOfAnyCell,
                                           mesh, why)) {
    vtkErrorMacro(<< "ROI Extract: " << why);
    return false;
  }

  std::vector<std::uint8_t> selected(static_cast<std::size_t>(n), 0);
  if (!this->PointIds.empty()) {
    for (vtkIdType id : this->PointIds) {
      if (id < 0 || id >= n) {
        vtkErrorMacro(<< "ROI Extract: point id " << id << " out of range [0, " << n << ")");
        return false;
      }
      selected[static_cast<std::size_t>(id)] = 1;
    }
  } else {
    for (vtkIdType i = 0; i < n; ++i) {
      double p[3];
      input->GetPoint(i, p);
      const double value = this->Region->FunctionValue(p);
      if (!std::isfinite(value)) {
        vtkErrorMacro(<< "ROI Extract: the Region gives a NaN or infinite value at point " << i
                      << ": its parameters (centre, origin, normal, position) must be finite");
        return false;
      }
      selected[static_cast<std::size_t>(i)] = value < 0.0 ? 1 : 0;
    }
  }
  if (this->InsideOut)
    for (auto& s : selected)
      s = s ? 0 : 1;

  faceplan::ROIResult roi;
  const faceplan::Status status = faceplan::ComputeROI(mesh, selected, roi);
  if (!status) {
    vtkErrorMacro(<< "ROI Extract: " << status.message);
    return false;
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
  if (roi.numROI == 0)
    vtkWarningMacro(<< "ROI Extract: the ROI is empty");
  return true;
}

void vtkROIExtract::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Region: " << this->Region << "\n";
  os << indent << "PointIds: " << this->PointIds.size() << " ids\n";
  os << indent << "InsideOut: " << this->InsideOut << "\n";
}
