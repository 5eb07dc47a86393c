// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Where a new ROI Extract's sphere starts: on the bone, where an operation would be planned, not
// over the whole bone (a sphere through the bounding box marks every vertex, and a cut of it
// shows nothing).
#include "Common/RowVectors3d.h"

#include <Eigen/Core>

namespace faceplan {

// The face frame of FacePlan's data (Data/README.md): anterior is -x, superior +z. The sphere is
// centred on the bone's most anterior point (a mandible's chin, a maxilla's incisor region), where
// contouring and genioplasty are planned, with a radius of kDefaultROIRadiusFraction of the bone's
// largest extent. False (outputs untouched) when there is no point or the extent is zero or not
// finite.
constexpr double kDefaultROIRadiusFraction = 0.2;
bool DefaultROISphere(const RowVectors3d& points, Eigen::Vector3d& centre, double& radius);

} // namespace faceplan
