#pragma once
// Step 1 of CondensedFEMDeform: every check on the inputs and properties that can be made before
// anything is converted or built, so that later steps (VTK locators, surface extraction, Core) only
// ever see well-formed data. Private to FacePlan::Filters.
#include "CondensedFEMDeformSettings.h"

#include "Common/Status.h"

#include <string>
#include <vector>

class vtkDataArray;
class vtkPointSet;
class vtkUnstructuredGrid;

namespace faceplan {
namespace fem_filter {

Status ValidateProperties(const Settings& settings);
Status ValidateTissue(vtkUnstructuredGrid* tissue, const Settings& settings);
Status ValidateBone(vtkPointSet* bone);
// The part of ValidateBone that an edit can change (points and Displacement), for a bone whose
// cells, point count and ROIMask passed ValidateBone before.
Status ValidateBoneValues(vtkPointSet* bone);

// After contact: a warning when the bone moves but no tied tissue node may follow it (the bone's
// ROIMask is 0 wherever the tissue is tied), which would otherwise give an all-zero result without
// a word; "" when there is nothing to say. `tiedMovable` is ContactMap::movable.
std::string UnfollowedBoneMotion(const std::vector<char>& tiedMovable,
                                 vtkDataArray* boneDisplacement);

} // namespace fem_filter
} // namespace faceplan
