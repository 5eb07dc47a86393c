// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A data set's identity and VTK modification times, the key of the filters' input caches: equal
// stamps mean equal content as long as whoever changes the data calls Modified() (VTK's contract).
// vtkDataObject::GetMTime covers the points and point/cell arrays but not the cell arrays of
// vtkPolyData and vtkUnstructuredGrid nor their storage, hence those are stamped one by one.
// Private to FacePlan::Filters.
#include "vtkType.h"

#include <vector>

class vtkObject;
class vtkPointSet;

namespace faceplan {

struct DataStamp {
  const void* object = nullptr;
  std::vector<const void*> arrays;
  std::vector<vtkMTimeType> times;
  bool operator==(const DataStamp& other) const {
    return object == other.object && arrays == other.arrays && times == other.times;
  }
  bool operator!=(const DataStamp& other) const { return !(*this == other); }
};

// Everything: the data object with its points and arrays, and its cells.
DataStamp StampOf(vtkPointSet* data);

// Adds one object (an array, a vtkCellArray; null allowed) with its modification time.
void AddToStamp(DataStamp& stamp, vtkObject* object);

// Adds the cell arrays of a vtkUnstructuredGrid or vtkPolyData (for any other vtkPointSet the data
// object's own time stands for its cells).
void AddCellsToStamp(DataStamp& stamp, vtkPointSet* data);

} // namespace faceplan
