// SPDX-License-Identifier: BSD-3-Clause
#include "BezierCut/DefaultCurves.h"

#include <algorithm>
#include <limits>

namespace faceplan {

bool DefaultCutCurves(const RowVectors3d& points, const std::vector<std::uint8_t>& mask,
                      const std::vector<std::uint8_t>& boundary,
                      std::vector<Eigen::Vector3d>& curveU, std::vector<Eigen::Vector3d>& curveV) {
  const Eigen::Index n = points.rows();
  const size_t count = static_cast<size_t>(n);
  const bool useMask = mask.size() == count &&
                       std::any_of(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; });
  const bool useBoundary = boundary.size() == count;
  constexpr double inf = std::numeric_limits<double>::infinity();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(inf), hi = -lo;
  Eigen::Vector3d boundaryLo = lo, boundaryHi = hi; // over the ROI's boundary points
  for (Eigen::Index i = 0; i < n; ++i) {
    if (useMask && !mask[static_cast<size_t>(i)])
      continue;
    const Eigen::Vector3d p = points.row(i).transpose();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    if (useBoundary && boundary[static_cast<size_t>(i)]) {
      boundaryLo = boundaryLo.cwiseMin(p);
      boundaryHi = boundaryHi.cwiseMax(p);
    }
  }
  const Eigen::Vector3d extent = hi - lo;
  if (!extent.allFinite() || extent.maxCoeff() <= 0.0)
    return false;

  // The normal: axis w, sign +1 or -1; `level` is where the plane crosses it.
  int w = 0;
  double sign = 1.0, level = 0.0;
  if (boundaryHi.allFinite()) {
    double bestRise = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      const double riseUp = hi[axis] - boundaryHi[axis], riseDown = boundaryLo[axis] - lo[axis];
      if (riseUp > bestRise) {
        bestRise = riseUp;
        w = axis;
        sign = 1.0;
        level = boundaryHi[axis] + kDefaultCutDepth * riseUp;
      }
      if (riseDown > bestRise) {
        bestRise = riseDown;
        w = axis;
        sign = -1.0;
        level = boundaryLo[axis] - kDefaultCutDepth * riseDown;
      }
    }
    if (bestRise <= 0.0)
      return false;
  } else {
    Eigen::Index shortest = 0;
    extent.minCoeff(&shortest);
    w = static_cast<int>(shortest);
    level = lo[w] + 0.75 * extent[w];
  }
  // (a, b, w) right-handed, so dS/du x dS/dv = a x b points along +w; swapped for -w.
  int a = (w + 1) % 3, b = (w + 2) % 3;
  if (sign < 0.0)
    std::swap(a, b);
  const double margin = 0.1;
  Eigen::Vector3d origin = lo;
  origin[a] -= margin * extent[a];
  origin[b] -= margin * extent[b];
  origin[w] = level;
  Eigen::Vector3d du = Eigen::Vector3d::Zero(), dv = Eigen::Vector3d::Zero();
  du[a] = (1.0 + 2.0 * margin) * extent[a];
  dv[b] = (1.0 + 2.0 * margin) * extent[b];
  if (!(du[a] > 0.0) || !(dv[b] > 0.0))
    return false;
  curveU.clear();
  curveV.clear();
  for (int k = 0; k < 4; ++k) {
    curveU.push_back(origin + (k / 3.0) * du);
    curveV.push_back(origin + (k / 3.0) * dv);
  }
  return true;
}

} // namespace faceplan
