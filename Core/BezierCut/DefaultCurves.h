// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Where a Bezier cut starts when the user has not placed its control points: a flat patch over the
// region of interest, so that a newly added cut meets the bone whatever its size and position.
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace faceplan {

// CurveU and CurveV (4 control points each, sharing the first) of a plane patch covering the
// bounding box of the ROI (points with mask != 0; all points when the mask selects none) across,
// with a 10% margin. Of the six axis directions the normal is the one along which the ROI's inner
// points rise highest above its boundary points (which never move); the plane lies kDefaultCutDepth
// of the way from the boundary's highest point to the ROI's (halfway), so the default Cut takes
// off a cap deep enough to see at the first Apply (4.8 mm on the default ROI of the bundled
// mandible) that stays clear of the ROI boundary. Without boundary points the normal is the box's
// shortest axis and the plane lies at three quarters of the box along it. Returns false (curves
// untouched) when the ROI has no extent to cut.
constexpr double kDefaultCutDepth = 0.5;
bool DefaultCutCurves(const RowVectors3d& points, const std::vector<std::uint8_t>& mask,
                      const std::vector<std::uint8_t>& boundary,
                      std::vector<Eigen::Vector3d>& curveU, std::vector<Eigen::Vector3d>& curveV);

} // namespace faceplan
