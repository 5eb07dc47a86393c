// SPDX-License-Identifier: BSD-3-Clause
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
// `undeformed` receives the undeformed bone (points minus Displacement, FacePlanUndeformedBone.h)
// that the check computes, for the caller to keep.
Status ValidateBone(vtkPointSet* bone, std::vector<double>& undeformed);
Status ValidateBone(vtkPointSet* bone);
// The part of ValidateBone that an edit can change (points and Displacement), for a bone whose
// cells, point count and ROIMask passed ValidateBone before.
Status ValidateBoneValues(vtkPointSet* bone, std::vector<double>& undeformed);

// After contact: a warning when the bone moves but no tied tissue node may follow it (the bone's
// ROIMask is 0 wherever the tissue is tied), which would otherwise give an all-zero result without
// a word; "" when there is nothing to say. `tiedMovable` is ContactMap::movable.
std::string UnfollowedBoneMotion(const std::vector<char>& tiedMovable,
                                 vtkDataArray* boneDisplacement);

// After the solve: a warning when the tissue moves much farther than any bone (by more than
// kLooseTissueRatio times the bone's largest Displacement), which is what a tissue held by too few
// bones does (only the operated segment connected, the fixed mandible or cranium left out); ""
// when there is nothing to say. Moves up to kLooseTissueFloor times `tissueSize` (the tissue's
// bounding-box diagonal) count as none. `tissueLargest` is the largest displacement of the
// tissue's surface, in mesh units; `lengthUnit` (metres per mesh unit) names the unit. Without
// gravity only: a sag is not a missing bone.
constexpr double kLooseTissueRatio = 1.5;
constexpr double kLooseTissueFloor = 1e-4;
std::string LooseTissueNote(double tissueLargest, vtkDataArray* boneDisplacement, double tissueSize,
                            double lengthUnit);

} // namespace fem_filter
} // namespace faceplan
