// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Voxel images in a physical frame, as Core sees them (no VTK): a CT volume in Hounsfield units and
// the label image made from it.
#include <Eigen/Core>
#include <Eigen/LU>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace faceplan {

// Labels of the tissue model. Mesh_3 treats 0 as outside the domain.
enum TissueLabel : std::uint8_t { kAir = 0, kSoftTissue = 1, kBone = 2, kMandible = 3 };

// Regular grid: voxel (i, j, k) sits at origin + direction * (i sx, j sy, k sz), the convention of
// vtkImageData. Voxels are stored with i fastest.
struct ImageGrid {
  std::array<int, 3> dims{{0, 0, 0}};
  std::array<double, 3> spacing{{1.0, 1.0, 1.0}};
  std::array<double, 3> origin{{0.0, 0.0, 0.0}};
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity(); // orthonormal; columns are the axes

  std::size_t numVoxels() const {
    return std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]);
  }
  std::size_t index(int i, int j, int k) const {
    return std::size_t(i) +
           std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * std::size_t(k));
  }
  double voxelVolume() const { return spacing[0] * spacing[1] * spacing[2]; }
  // A point given in the grid's own scaled frame (index times spacing, no origin or rotation) in
  // the physical frame, and back.
  Eigen::Vector3d toWorld(const Eigen::Vector3d& scaled) const {
    return Eigen::Vector3d(origin[0], origin[1], origin[2]) + direction * scaled;
  }
  Eigen::Vector3d toScaled(const Eigen::Vector3d& world) const {
    return direction.transpose() * (world - Eigen::Vector3d(origin[0], origin[1], origin[2]));
  }
};

struct CTImage {
  ImageGrid grid;
  std::vector<float> hounsfield; // one value per voxel
};

struct LabelImage {
  ImageGrid grid;
  std::vector<std::uint8_t> labels; // TissueLabel per voxel
};

} // namespace faceplan
