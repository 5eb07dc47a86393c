// SPDX-License-Identifier: BSD-3-Clause
#include "FacePlanDataStamp.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

namespace faceplan {

namespace {

void AddCells(DataStamp& stamp, vtkCellArray* cells) {
  AddToStamp(stamp, cells);
  if (cells) {
    AddToStamp(stamp, cells->GetConnectivityArray());
    AddToStamp(stamp, cells->GetOffsetsArray());
  }
}

} // namespace

void AddToStamp(DataStamp& stamp, vtkObject* object) {
  stamp.arrays.push_back(object);
  stamp.times.push_back(object ? object->GetMTime() : 0);
}

void AddCellsToStamp(DataStamp& stamp, vtkPointSet* data) {
  if (auto* grid = vtkUnstructuredGrid::SafeDownCast(data)) {
    AddCells(stamp, grid->GetCells());
    AddToStamp(stamp, grid->GetCellTypesArray());
  } else if (auto* poly = vtkPolyData::SafeDownCast(data)) {
    AddCells(stamp, poly->GetVerts());
    AddCells(stamp, poly->GetLines());
    AddCells(stamp, poly->GetPolys());
    AddCells(stamp, poly->GetStrips());
  } else {
    stamp.times.push_back(data->GetMTime());
  }
}

DataStamp StampOf(vtkPointSet* data) {
  DataStamp stamp;
  stamp.object = data;
  stamp.times.push_back(data->GetMTime()); // points, point and cell data
  AddToStamp(stamp, data->GetPoints());
  AddCellsToStamp(stamp, data);
  return stamp;
}

} // namespace faceplan
