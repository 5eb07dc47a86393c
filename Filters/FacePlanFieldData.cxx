// SPDX-License-Identifier: BSD-3-Clause
#include "FacePlanFieldData.h"

#include <vtkAbstractArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationIntegerKey.h>
#include <vtkNew.h>
#include <vtkStringArray.h>

namespace faceplan {
namespace fielddata {

void AddScalar(vtkFieldData* fd, const char* name, double value) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  fd->AddArray(a);
}

void AddString(vtkFieldData* fd, const char* name, const std::string& value) {
  vtkNew<vtkStringArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  fd->AddArray(a);
}

void HideFromArrayLists(vtkFieldData* fd) {
  for (int i = 0; fd && i < fd->GetNumberOfArrays(); ++i)
    if (vtkAbstractArray* array = fd->GetAbstractArray(i))
      array->GetInformation()->Set(vtkAbstractArray::GUI_HIDE(), 1);
}

} // namespace fielddata
} // namespace faceplan
