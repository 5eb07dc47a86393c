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

} // namespace fielddata
} // namespace faceplan
