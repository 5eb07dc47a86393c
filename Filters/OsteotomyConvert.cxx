// SPDX-License-Identifier: BSD-3-Clause
#include "OsteotomyConvert.h"

#include "FacePlanVTKConvert.h"

#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkImplicitFunction.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>

#include <cmath>
#include <string>

namespace faceplan {
namespace osteotomy_filter {

namespace {

vtkSmartPointer<vtkDoubleArray> ZeroArray(const char* name, int components, vtkIdType n) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  a->FillValue(0.0);
  return a;
}

} // namespace

bool IsBookkeepingArray(const std::string& name) {
  return name == "Displacement" || name == "ROIMask" || name == "SegmentId";
}

bool IsCarriedArray(vtkDataArray* array) {
  return array->GetName() && !IsBookkeepingArray(array->GetName()) &&
         array->GetNumberOfComponents() == 1;
}

Status ValidateInput(vtkDataSet* data) {
  vtkPolyData* input = vtkPolyData::SafeDownCast(data);
  if (!input)
    return Status::Error(
        std::string("the input is a ") + (data ? data->GetClassName() : "null data set") +
        "; Osteotomy needs a bone surface of triangles (apply Extract Surface first)");
  if (input->GetNumberOfPoints() == 0 ||
      input->GetNumberOfPolys() + input->GetNumberOfStrips() == 0)
    return Status::Error("the input has no triangles; Osteotomy needs a bone surface of triangles");
  if (input->GetNumberOfLines() + input->GetNumberOfVerts() > 0)
    return Status::Error("the input has " +
                         std::to_string(input->GetNumberOfLines() + input->GetNumberOfVerts()) +
                         " line or vertex cells; Osteotomy needs a bone surface of triangles only");
  vtkDataArray* displacement = input->GetPointData()->GetArray("Displacement");
  if (displacement && displacement->GetNumberOfComponents() != 3)
    return Status::Error("the input's Displacement array does not have 3 components");
  return Status::Ok();
}

Status ToCutPlanes(const std::vector<vtkImplicitFunction*>& functions,
                   std::vector<CutPlane>& planes) {
  planes.assign(functions.size(), CutPlane());
  for (std::size_t k = 0; k < functions.size(); ++k) {
    vtkPlane* plane = vtkPlane::SafeDownCast(functions[k]);
    if (!plane)
      return Status::Error("CutPlane" + std::to_string(k + 1) + " is not set or not a plane");
    // The gradient is the normal; the origin moves onto the zero set.
    double o[3], g[3];
    plane->GetOrigin(o);
    plane->FunctionGradient(o, g);
    const double value = plane->FunctionValue(o);
    planes[k].normal = Eigen::Vector3d(g[0], g[1], g[2]);
    planes[k].origin = Eigen::Vector3d(o[0], o[1], o[2]);
    if (value != 0.0)
      planes[k].origin -= (value / planes[k].normal.squaredNorm()) * planes[k].normal;
  }
  return NormalizeCutPlanes(planes);
}

vtkSmartPointer<vtkPolyData> BookkeepingBone(vtkPolyData* input) {
  auto bone = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkTriangleFilter> triangulate;
  triangulate->SetInputData(input);
  triangulate->Update();
  bone->CopyStructure(triangulate->GetOutput());
  const vtkIdType n = input->GetNumberOfPoints();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i)
    points->SetPoint(i, input->GetPoint(i));
  bone->SetPoints(points);
  auto displacement = ZeroArray("Displacement", 3, n);
  auto mask = ZeroArray("ROIMask", 1, n);
  auto segment = ZeroArray("SegmentId", 1, n);
  vtkDataArray* inDisplacement = input->GetPointData()->GetArray("Displacement");
  vtkDataArray* inMask = input->GetPointData()->GetArray("ROIMask");
  vtkDataArray* inSegment = input->GetPointData()->GetArray("SegmentId");
  for (vtkIdType i = 0; i < n; ++i) {
    if (inDisplacement)
      for (int c = 0; c < 3; ++c)
        displacement->SetComponent(i, c, inDisplacement->GetComponent(i, c));
    if (inMask)
      mask->SetValue(i, inMask->GetComponent(i, 0) != 0.0 ? 1.0 : 0.0);
    if (inSegment)
      segment->SetValue(i, inSegment->GetComponent(i, 0));
  }
  bone->GetPointData()->AddArray(displacement);
  bone->GetPointData()->AddArray(mask);
  bone->GetPointData()->AddArray(segment);
  vtkPointData* carried = input->GetPointData();
  for (int a = 0; a < carried->GetNumberOfArrays(); ++a)
    if (vtkDataArray* array = carried->GetArray(a))
      if (IsCarriedArray(array))
        bone->GetPointData()->AddArray(array);
  return bone;
}

Status ToOsteotomyBone(vtkPolyData* split, const std::vector<std::uint8_t>& moves,
                       vtkFieldData* inputField, OsteotomyBone& bone) {
  bone = OsteotomyBone();
  std::string why;
  if (!vtkconvert::ToSurfaceMesh(split, vtkconvert::CellPolicy::SurfaceOnly, bone.mesh, why))
    return Status::Error(why);
  const vtkIdType n = split->GetNumberOfPoints();
  bone.displacement.resize(n, 3);
  bone.segmentId.resize(static_cast<std::size_t>(n));
  bone.roiMask.resize(static_cast<std::size_t>(n));
  bone.moves = moves;
  if (n > 0) {
    vtkDataArray* d = split->GetPointData()->GetArray("Displacement");
    vtkDataArray* r = split->GetPointData()->GetArray("ROIMask");
    vtkDataArray* s = split->GetPointData()->GetArray("SegmentId");
    if (!d || !r || !s)
      return Status::Error("clipping lost the bone's point arrays");
    for (vtkIdType i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c)
        bone.displacement(i, c) = d->GetComponent(i, c);
      // A new point lies on an edge of one piece of the input, whose ends share a segment id.
      bone.segmentId[static_cast<std::size_t>(i)] =
          static_cast<int>(std::lround(s->GetComponent(i, 0)));
      bone.roiMask[static_cast<std::size_t>(i)] = r->GetComponent(i, 0) >= 0.5 ? 1 : 0;
    }
  }
  if (vtkDataArray* t = inputField->GetArray("SegmentTransform")) {
    const int m = t->GetNumberOfComponents();
    for (vtkIdType k = 0; k < t->GetNumberOfTuples() * m; ++k)
      bone.segmentTransforms.push_back(t->GetComponent(k / m, k % m));
  }
  if (auto* notes = vtkStringArray::SafeDownCast(inputField->GetAbstractArray("SegmentNote")))
    for (vtkIdType k = 0; k < notes->GetNumberOfValues(); ++k)
      bone.segmentNotes.push_back(notes->GetValue(k));
  return Status::Ok();
}

} // namespace osteotomy_filter
} // namespace faceplan
