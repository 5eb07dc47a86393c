// SPDX-License-Identifier: BSD-3-Clause
#include "FacePlanArrayRanges.h"

#include <vtkAOSDataArrayTemplate.h>
#include <vtkCellData.h>
#include <vtkCompositeDataIterator.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkDataSet.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationDoubleVectorKey.h>
#include <vtkInformationInformationVectorKey.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkTable.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>
#include <vector>

namespace faceplan {
namespace {

// Per component min and max, and min and max of the tuple's Euclidean norm, as VTK computes them
// (values converted to double, the norm's square summed over the components in order, the square
// root taken of the extremes). False when a value is not finite (VTK's two variants then differ).
template <typename T>
bool ComputeRanges(vtkAOSDataArrayTemplate<T>* array, std::vector<double>& components,
                   double norm[2]) {
  const int nc = array->GetNumberOfComponents();
  const vtkIdType nt = array->GetNumberOfTuples();
  const T* values = array->GetPointer(0);
  components.resize(2 * static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c) {
    components[2 * c] = std::numeric_limits<double>::max();
    components[2 * c + 1] = std::numeric_limits<double>::lowest();
  }
  double low = std::numeric_limits<double>::max(), high = std::numeric_limits<double>::lowest();
  for (vtkIdType t = 0; t < nt; ++t) {
    double squared = 0.0;
    for (int c = 0; c < nc; ++c) {
      const double x = static_cast<double>(values[t * nc + c]);
      if (!std::isfinite(x))
        return false;
      components[2 * c] = std::min(components[2 * c], x);
      components[2 * c + 1] = std::max(components[2 * c + 1], x);
      squared += x * x;
    }
    low = std::min(low, squared);
    high = std::max(high, squared);
  }
  norm[0] = std::sqrt(low);
  norm[1] = std::sqrt(high);
  return true;
}

void Store(vtkDataArray* array, const std::vector<double>& components, const double norm[2]) {
  vtkInformation* info = array->GetInformation();
  info->Set(vtkDataArray::L2_NORM_RANGE(), norm, 2);
  info->Set(vtkDataArray::L2_NORM_FINITE_RANGE(), norm, 2);
  for (vtkInformationInformationVectorKey* key :
       {vtkDataArray::PER_COMPONENT(), vtkDataArray::PER_FINITE_COMPONENT()}) {
    vtkNew<vtkInformationVector> perComponent;
    perComponent->SetNumberOfInformationObjects(array->GetNumberOfComponents());
    for (int c = 0; c < array->GetNumberOfComponents(); ++c)
      perComponent->GetInformationObject(c)->Set(vtkDataArray::COMPONENT_RANGE(),
                                                 components.data() + 2 * c, 2);
    info->Set(key, perComponent);
  }
}

void Cache(vtkDataArray* array) {
  if (!array || array->GetNumberOfTuples() == 0 || array->GetNumberOfComponents() == 0)
    return;
  std::vector<double> components;
  double norm[2];
  bool computed = false;
  switch (array->GetDataType()) {
    vtkTemplateMacro(if (auto* aos = vtkAOSDataArrayTemplate<VTK_TT>::FastDownCast(array))
                         computed = ComputeRanges(aos, components, norm););
  default:
    break;
  }
  if (computed)
    Store(array, components, norm);
}

// Calls visit(array) for the points' array and each array of the point, cell, row and field data
// of `data`, or of each of its leaves.
template <typename Visit> void ForEachArray(vtkDataObject* data, const Visit& visit) {
  if (!data)
    return;
  auto field = [&visit](vtkFieldData* fd) {
    for (int i = 0; fd && i < fd->GetNumberOfArrays(); ++i)
      visit(fd->GetAbstractArray(i));
  };
  if (auto* composite = vtkCompositeDataSet::SafeDownCast(data)) {
    vtkSmartPointer<vtkCompositeDataIterator> it;
    it.TakeReference(composite->NewIterator());
    for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
      ForEachArray(it->GetCurrentDataObject(), visit);
  }
  if (auto* pointSet = vtkPointSet::SafeDownCast(data))
    if (vtkPoints* points = pointSet->GetPoints())
      visit(points->GetData());
  if (auto* dataSet = vtkDataSet::SafeDownCast(data)) {
    field(dataSet->GetPointData());
    field(dataSet->GetCellData());
  }
  if (auto* table = vtkTable::SafeDownCast(data))
    field(table->GetRowData());
  field(data->GetFieldData());
}

} // namespace

void CacheArrayRanges(vtkDataObject* output, const std::vector<vtkDataObject*>& inputs) {
  std::unordered_set<const vtkAbstractArray*> held;
  for (vtkDataObject* input : inputs)
    ForEachArray(input, [&held](vtkAbstractArray* array) { held.insert(array); });
  ForEachArray(output, [&held](vtkAbstractArray* array) {
    if (!held.count(array))
      Cache(vtkDataArray::SafeDownCast(array));
  });
}

} // namespace faceplan
