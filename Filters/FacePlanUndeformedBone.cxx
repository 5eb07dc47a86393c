// SPDX-License-Identifier: BSD-3-Clause
#include "FacePlanUndeformedBone.h"

#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkNew.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"

namespace faceplan {

void UndeformedPoints(vtkPointSet* bone, vtkDataArray* displacement, std::vector<double>& out) {
  const vtkIdType n = bone->GetNumberOfPoints();
  out.resize(static_cast<size_t>(3 * n));
  auto* p =
      bone->GetPoints() ? vtkDoubleArray::FastDownCast(bone->GetPoints()->GetData()) : nullptr;
  auto* d = vtkDoubleArray::FastDownCast(displacement);
  if (p && d) { // BezierCut's and Osteotomy's output: no per-value virtual calls
    const double* x = p->GetPointer(0);
    const double* u = d->GetPointer(0);
    for (vtkIdType k = 0; k < 3 * n; ++k)
      out[k] = x[k] - u[k];
    return;
  }
  for (vtkIdType i = 0; i < n; ++i) {
    double x[3], u[3];
    bone->GetPoint(i, x);
    displacement->GetTuple(i, u);
    for (int c = 0; c < 3; ++c)
      out[3 * i + c] = x[c] - u[c];
  }
}

vtkSmartPointer<vtkPointSet> UndeformedBone(vtkPointSet* bone, const std::vector<double>& points) {
  vtkSmartPointer<vtkPointSet> undeformed;
  undeformed.TakeReference(bone->NewInstance());
  undeformed->CopyStructure(bone);
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(bone->GetNumberOfPoints());
  std::copy(points.begin(), points.end(), coordinates->GetPointer(0));
  vtkNew<vtkPoints> undeformedPoints;
  undeformedPoints->SetData(coordinates);
  undeformed->SetPoints(undeformedPoints);
  return undeformed;
}

} // namespace faceplan
