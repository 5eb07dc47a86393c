#pragma once
// Step 1 of CondensedFEMDeform: every check on the inputs and properties that can be made before
// anything is converted or built, so that later steps (VTK locators, surface extraction, Core) only
// ever see well-formed data. Private to FacePlan::Filters.
#include "CondensedFEMDeformSettings.h"

#include "Common/Status.h"

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

} // namespace fem_filter
} // namespace faceplan
