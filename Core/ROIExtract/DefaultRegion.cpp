// SPDX-License-Identifier: BSD-3-Clause
#include "ROIExtract/DefaultRegion.h"

#include <cmath>

namespace faceplan {

bool DefaultROISphere(const RowVectors3d& points, Eigen::Vector3d& centre, double& radius) {
  if (points.rows() == 0 || !points.allFinite())
    return false;
  const Eigen::Vector3d lo = points.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = points.colwise().maxCoeff().transpose();
  const double extent = (hi - lo).maxCoeff();
  if (!(extent > 0.0) || !std::isfinite(extent))
    return false;
  Eigen::Index front = 0;
  points.col(0).minCoeff(&front);
  centre = points.row(front).transpose();
  radius = kDefaultROIRadiusFraction * extent;
  return true;
}

} // namespace faceplan
