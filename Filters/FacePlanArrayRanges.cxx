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
// root taken of the extremes). False when a value is not finite (VTK's two variants then differ):
// x - x is 0 for a finite x and NaN otherwise, so their sum tells without a branch per value.
// NC > 0: that many components, kept in registers; 0: any number.
template <int NC, typename T>
bool ScanRanges(const T* values, vtkIdType nt, int nc, double* components, double norm[2]) {
  constexpr int kFixed = NC > 0 ? NC : 1;
  double fixedLow[kFixed], fixedHigh[kFixed];
  std::vector<double> anyLow, anyHigh;
  double* low = fixedLow;
  double* high = fixedHigh;
  if (NC == 0) {
    anyLow.resize(static_cast<std::size_t>(nc));
    anyHigh.resize(static_cast<std::size_t>(nc));
    low = anyLow.data();
    high = anyHigh.data();
  } else {
    nc = NC;
  }
  std::fill(low, low + nc, std::numeric_limits<double>::max());
  std::fill(high, high + nc, std::numeric_limits<double>::lowest());
  double normLow = std::numeric_limits<double>::max();
  double normHigh = std::numeric_limits<double>::lowest();
  double nonFinite = 0.0;
  for (vtkIdType t = 0; t < nt; ++t) {
    const T* tuple = values + t * nc;
    double squared = 0.0;
    for (int c = 0; c < nc; ++c) {
      const double x = static_cast<double>(tuple[c]);
      low[c] = x < low[c] ? x : low[c];
      high[c] = x > high[c] ? x : high[c];
      squared += x * x;
      nonFinite += x - x;
    }
    normLow = squared < normLow ? squared : normLow;
    normHigh = squared > normHigh ? squared : normHigh;
  }
  if (nonFinite != 0.0) // NaN compares unequal
    return false;
  for (int c = 0; c < nc; ++c) {
    components[2 * c] = low[c];
    components[2 * c + 1] = high[c];
  }
  norm[0] = std::sqrt(normLow);
  norm[1] = std::sqrt(normHigh);
  return true;
}

template <typename T>
bool ComputeRanges(vtkAOSDataArrayTemplate<T>* array, std::vector<double>& components,
                   double norm[2]) {
  const int nc = array->GetNumberOfComponents();
  const vtkIdType nt = array->GetNumberOfTuples();
  const T* values = array->GetPointer(0);
  components.resize(2 * static_cast<std::size_t>(nc));
  switch (nc) {
  case 1:
    return ScanRanges<1>(values, nt, nc, components.data(), norm);
  case 2:
    return ScanRanges<2>(values, nt, nc, components.data(), norm);
  case 3:
    return ScanRanges<3>(values, nt, nc, components.data(), norm);
  default:
    return ScanRanges<0>(values, nt, nc, components.data(), norm);
  }
}

void Store(vtkDataArray* array, const std::vector<double>& components, const double norm[2]) {
  vtkInformation* info = array->GetInformation();
  info->Set(vtkDataArray::L2_NORM_RANGE(), norm, 2);
  info->Set(vtkDataArray::L2_NORM_FINITE_RANGE(), norm, 2);
  const int nc = array->GetNumberOfComponents();
  for (vtkInformationInformationVectorKey* key :
       {vtkDataArray::PER_COMPONENT(), vtkDataArray::PER_FINITE_COMPONENT()}) {
    vtkInformationVector* perComponent = info->Get(key);
    if (!perComponent || perComponent->GetNumberOfInformationObjects() < nc) {
      // As vtkDataArray::ComputeRange makes it: FastDelete, since an information vector's plain
      // Delete runs VTK's garbage collector, which costs more than the whole scan.
      perComponent = vtkInformationVector::New();
      perComponent->SetNumberOfInformationObjects(nc);
      info->Set(key, perComponent);
      perComponent->FastDelete();
    }
    for (int c = 0; c < nc; ++c)
      perComponent->GetInformationObject(c)->Set(vtkDataArray::COMPONENT_RANGE(),
                                                 components.data() + 2 * c, 2);
  }
}

// Whether VTK would take array's ranges from its cache: all four kinds stored since the array
// last changed (an array the filter keeps from one update to the next, unchanged).
bool CachedAndValid(vtkDataArray* array) {
  vtkInformation* info = array->GetInformation();
  if (info->GetMTime() < array->GetMTime() || !info->Has(vtkDataArray::L2_NORM_RANGE()) ||
      !info->Has(vtkDataArray::L2_NORM_FINITE_RANGE()))
    return false;
  for (vtkInformationInformationVectorKey* key :
       {vtkDataArray::PER_COMPONENT(), vtkDataArray::PER_FINITE_COMPONENT()}) {
    vtkInformationVector* perComponent = info->Get(key);
    if (!perComponent ||
        perComponent->GetNumberOfInformationObjects() < array->GetNumberOfComponents())
      return false;
    for (int c = 0; c < array->GetNumberOfComponents(); ++c)
      if (!perComponent->GetInformationObject(c)->Has(vtkDataArray::COMPONENT_RANGE()))
        return false;
  }
  return true;
}

// Arrays of fewer values (the field data's one-value figures) are left to VTK, so that a script
// that never asks for ranges does not pay for them; ParaView's data information computes them.
constexpr vtkIdType kSmallestCached = 64;

void Cache(vtkDataArray* array) {
  if (!array || array->GetNumberOfValues() < kSmallestCached ||
      array->GetNumberOfComponents() == 0 || CachedAndValid(array))
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
