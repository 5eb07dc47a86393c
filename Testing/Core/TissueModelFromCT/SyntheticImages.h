// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Labelled and CT test images with known geometry: a soft-tissue shell around a bone ball, the
// sizes of the analytic hollow sphere (Support/AnalyticHollowSphere.h).
#include "TissueModelFromCT/LabelImage.h"

#include <cmath>

namespace faceplan {
namespace testimages {

// Ball of radius a (bone) inside a shell up to radius b (soft tissue), centred at `centre`
// (physical frame), sampled at voxel centres on a cube of half-width `halfWidth` around it.
inline LabelImage ShellAroundBall(double a, double b, double voxel, double halfWidth,
                                  const Eigen::Vector3d& centre = Eigen::Vector3d::Zero(),
                                  const Eigen::Matrix3d& direction = Eigen::Matrix3d::Identity()) {
  LabelImage image;
  const int n = int(std::ceil(2.0 * halfWidth / voxel)) + 1;
  image.grid.dims = {n, n, n};
  image.grid.spacing = {voxel, voxel, voxel};
  image.grid.direction = direction;
  const Eigen::Vector3d origin = centre - direction * Eigen::Vector3d::Constant(halfWidth);
  image.grid.origin = {origin[0], origin[1], origin[2]};
  image.labels.resize(image.grid.numVoxels());
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d x =
            image.grid.toWorld(Eigen::Vector3d(i * voxel, j * voxel, k * voxel));
        const double r = (x - centre).norm();
        image.labels[image.grid.index(i, j, k)] = r < a ? kBone : (r < b ? kSoftTissue : kAir);
      }
  return image;
}

// The same scene as a CT: air -1000 HU, soft tissue 40 HU, bone 1000 HU.
inline CTImage AsCT(const LabelImage& labels) {
  CTImage ct;
  ct.grid = labels.grid;
  ct.hounsfield.resize(labels.labels.size());
  for (std::size_t v = 0; v < labels.labels.size(); ++v)
    ct.hounsfield[v] =
        labels.labels[v] == kAir ? -1000.0f : (labels.labels[v] == kSoftTissue ? 40.0f : 1000.0f);
  return ct;
}

} // namespace testimages
} // namespace faceplan
