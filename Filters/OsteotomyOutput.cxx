// SPDX-License-Identifier: BSD-3-Clause
#include "OsteotomyOutput.h"

#include "OsteotomyConvert.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkUnsignedCharArray.h>

namespace faceplan {
namespace osteotomy_filter {

void BuildBoneOutput(const OsteotomyResult& result, vtkPolyData* split, vtkFieldData* inputField,
                     vtkPolyData* output) {
  vtkCellArray* triangles = split->GetPolys();
  const vtkIdType n = result.points.rows();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  displacement->SetNumberOfTuples(n);
  vtkNew<vtkUnsignedCharArray> mask;
  mask->SetName("ROIMask");
  mask->SetNumberOfTuples(n);
  vtkNew<vtkIntArray> segment;
  segment->SetName("SegmentId");
  segment->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i) {
    const std::size_t ui = static_cast<std::size_t>(i);
    points->SetPoint(i, result.points(i, 0), result.points(i, 1), result.points(i, 2));
    displacement->SetTuple3(i, result.displacement(i, 0), result.displacement(i, 1),
                            result.displacement(i, 2));
    mask->SetValue(i, result.roiMask[ui]);
    segment->SetValue(i, result.segmentId[ui]);
  }
  output->SetPoints(points);
  output->SetPolys(triangles);
  output->GetPointData()->AddArray(displacement);
  output->GetPointData()->SetActiveVectors("Displacement");
  output->GetPointData()->AddArray(mask);
  output->GetPointData()->AddArray(segment);
  vtkPointData* carried = split->GetPointData();
  for (int a = 0; a < carried->GetNumberOfArrays(); ++a)
    if (vtkDataArray* array = carried->GetArray(a))
      if (IsCarriedArray(array) && array->GetNumberOfTuples() == n)
        output->GetPointData()->AddArray(array);

  vtkNew<vtkFieldData> field;
  field->ShallowCopy(inputField);
  vtkNew<vtkDoubleArray> transforms;
  transforms->SetName("SegmentTransform");
  for (double v : result.segmentTransforms)
    transforms->InsertNextValue(v);
  vtkNew<vtkStringArray> notes;
  notes->SetName("SegmentNote");
  for (const std::string& note : result.segmentNotes)
    notes->InsertNextValue(note);
  field->RemoveArray("SegmentTransform");
  field->RemoveArray("SegmentNote");
  field->AddArray(transforms);
  field->AddArray(notes);
  output->SetFieldData(field);
}

void BuildCutPlaneOutput(const std::vector<CutPlane>& planes, const std::array<double, 6>& box,
                         vtkPolyData* output) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> polygons;
  vtkNew<vtkIntArray> ids;
  ids->SetName("CutPlane");
  for (std::size_t k = 0; k < planes.size(); ++k) {
    const std::vector<Eigen::Vector3d> corners = PlaneBoxSection(planes[k], box);
    if (corners.empty())
      continue;
    polygons->InsertNextCell(static_cast<vtkIdType>(corners.size()));
    for (const Eigen::Vector3d& c : corners)
      polygons->InsertCellPoint(points->InsertNextPoint(c.data()));
    ids->InsertNextValue(static_cast<int>(k + 1));
  }
  output->SetPoints(points);
  output->SetPolys(polygons);
  output->GetCellData()->AddArray(ids);
}

} // namespace osteotomy_filter
} // namespace faceplan
