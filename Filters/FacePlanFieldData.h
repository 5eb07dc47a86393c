// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One-value field-data arrays: the figures the filters report beside their outputs (solve time,
// residual, mesh quality, ...), readable in the Information panel and from pvpython.
#include <string>

class vtkFieldData;

namespace faceplan {
namespace fielddata {

// Adds (or replaces) a one-tuple vtkDoubleArray / vtkStringArray named `name`.
void AddScalar(vtkFieldData* fd, const char* name, double value);
void AddString(vtkFieldData* fd, const char* name, const std::string& value);

// Keeps every array of `fd` out of ParaView's colour-by list (and its other array menus) while
// the Information panel, pvpython and scripts still read it, by name and value unchanged: marks
// it vtkAbstractArray::GUI_HIDE, which ParaView's array-list domains reject by default. A figure
// of one value colours nothing. Only for arrays the filter made itself (inputs are not modified).
void HideFromArrayLists(vtkFieldData* fd);

} // namespace fielddata
} // namespace faceplan
