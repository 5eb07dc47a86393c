// SPDX-License-Identifier: BSD-3-Clause
#include "BezierCutInputCache.h"

#include "FacePlanVTKConvert.h"

#include "BezierCut/DefaultCurves.h"

#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>

#include <cmath>
#include <string>

namespace faceplan {
namespace bezier_filter {

namespace {

vtkIdType CountSurfaceCells(vtkPointSet* input) {
  vtkIdType count = 0;
  for (vtkIdType c = 0; c < input->GetNumberOfCells(); ++c) {
    const int type = input->GetCellType(c);
    count += type == VTK_TRIANGLE || type == VTK_QUAD || type == VTK_POLYGON || type == VTK_PIXEL ||
             type == VTK_TRIANGLE_STRIP;
  }
  return count;
}

} // namespace

Status InputCache::update(vtkPointSet* input) {
  DataStamp stamp = StampOf(input);
  if (valid_ && stamp == stamp_)
    return Status::Ok();
  valid_ = false;
  const Status status = this->convert(input);
  if (!status) {
    mesh_ = SurfaceMesh{};
    topology_ = CutMeshTopology{};
    mask_.clear();
    boundary_.clear();
    points_ = nullptr;
    return status;
  }
  stamp_ = std::move(stamp);
  valid_ = true;
  ++conversions_;
  return Status::Ok();
}

Status InputCache::convert(vtkPointSet* input) {
  const vtkIdType n = input->GetNumberOfPoints();
  if (n == 0)
    return Status::Error("the input has no points");
  vtkDataArray* maskArray = input->GetPointData()->GetArray("ROIMask");
  vtkDataArray* boundaryArray = input->GetPointData()->GetArray("ROIBoundary");
  if (!maskArray || !boundaryArray || maskArray->GetNumberOfComponents() != 1 ||
      boundaryArray->GetNumberOfComponents() != 1)
    return Status::Error("the input needs one-component point arrays ROIMask and ROIBoundary; "
                         "apply ROI Extract first");
  for (vtkDataArray* a : {maskArray, boundaryArray}) {
    if (a->GetNumberOfTuples() != n)
      return Status::Error(std::string("the point array ") + a->GetName() + " has " +
                           std::to_string(a->GetNumberOfTuples()) +
                           " values; it needs one per point (" + std::to_string(n) + ")");
    for (vtkIdType i = 0; i < n; ++i)
      if (!std::isfinite(a->GetComponent(i, 0)))
        return Status::Error(std::string("the point array ") + a->GetName() +
                             " has a NaN or infinite value at point " + std::to_string(i));
  }

  std::string why;
  if (!vtkconvert::ToSurfaceMesh(input, vtkconvert::CellPolicy::SurfaceOnly, mesh_, why))
    return Status::Error(why);
  skipped_ = input->GetNumberOfCells() - CountSurfaceCells(input);
  if (mesh_.numCells() == 0)
    return Status::Error("the input has no surface cells (triangles or polygons) to cut; lines "
                         "and vertices cannot be cut");
  mask_.assign(static_cast<std::size_t>(n), 0);
  boundary_.assign(static_cast<std::size_t>(n), 0);
  for (vtkIdType i = 0; i < n; ++i) {
    mask_[static_cast<std::size_t>(i)] = maskArray->GetComponent(i, 0) != 0.0;
    boundary_[static_cast<std::size_t>(i)] = boundaryArray->GetComponent(i, 0) != 0.0;
  }
  const Status status = PrepareCutMesh(mesh_, topology_);
  if (!status)
    return status;
  defaultU_.clear();
  defaultV_.clear();
  hasDefaults_ = DefaultCutCurves(mesh_.points, mask_, boundary_, defaultU_, defaultV_);

  points_ = vtkSmartPointer<vtkDoubleArray>::New();
  points_->SetNumberOfComponents(3);
  points_->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
    points_->SetTuple(i, input->GetPoints()->GetPoint(i));
  return Status::Ok();
}

} // namespace bezier_filter
} // namespace faceplan
