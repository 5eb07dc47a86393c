// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The undeformed bone: the bone's points minus its point array Displacement, the bone before the
// operation moved it. Contact is defined there, validation checks it, the contact cache compares
// it and the rigid segments are checked from it: one definition for all of them.
// Private to FacePlan::Filters (and the contact fuzz target).
#include "vtkSmartPointer.h"

#include <vector>

class vtkDataArray;
class vtkPointSet;

namespace faceplan {

// points - displacement as 3n doubles (x0 y0 z0 x1 ...). `displacement` has 3 components and one
// tuple per point (validated before).
void UndeformedPoints(vtkPointSet* bone, vtkDataArray* displacement, std::vector<double>& out);

// A data set with the bone's cells and the given undeformed points (3n doubles), no arrays.
vtkSmartPointer<vtkPointSet> UndeformedBone(vtkPointSet* bone, const std::vector<double>& points);

} // namespace faceplan
