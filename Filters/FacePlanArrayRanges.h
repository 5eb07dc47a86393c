// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The value ranges of a filter's new output arrays, stored where VTK keeps them cached.
//
// After every update ParaView describes each new output (its data information: bounds, and each
// array's range per component, of its magnitude, of all and of finite values) for the Information
// panel, the colour maps and the array-list domains. vtkDataArray computes a range once and keeps
// it in its information (COMPONENT_RANGE, L2_NORM_RANGE and their finite twins) until the array is
// modified; an array made anew by each update is computed anew, by VTK's generic code, in several
// passes over it. During a drag that is a large part of what the GUI does per move for arrays
// FacePlan has just made. Here one pass over each new array fills the same cache with the values
// VTK would compute, so that ParaView finds them there.
//
// Only arrays the filter made are touched: one also held by an input (a shallow-copied pass-through
// array) is left alone, since inputs are never modified; so is one whose ranges are cached already
// (an array kept unchanged from the last update). Arrays of fewer than 64 values, arrays with a
// non-finite value and arrays not stored as one contiguous block are left to VTK. Call it last,
// once the output is complete: modifying an array afterwards invalidates its cached ranges, as in
// VTK.
// Private to FacePlan::Filters.
#include <vector>

class vtkDataObject;

namespace faceplan {

// Caches the ranges of every vtkDataArray of `output` (points, point, cell, row and field data;
// each leaf of a composite data set) that none of `inputs` holds.
void CacheArrayRanges(vtkDataObject* output, const std::vector<vtkDataObject*>& inputs);

} // namespace faceplan
