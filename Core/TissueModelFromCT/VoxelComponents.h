// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Connected components (6-connectivity) of a voxel mask.
#include <array>
#include <cstdint>
#include <vector>

namespace faceplan {

struct VoxelComponents {
  std::vector<int> id;                     // per voxel: its component, -1 outside the mask
  std::vector<long long> sizes;            // voxels per component
  std::vector<std::uint8_t> touchesBorder; // per component: has a voxel on the image border
};

VoxelComponents FindComponents(const std::vector<std::uint8_t>& mask,
                               const std::array<int, 3>& dims);

// Clears every voxel of the mask outside its largest component.
void KeepLargestComponent(std::vector<std::uint8_t>& mask, const std::array<int, 3>& dims);

} // namespace faceplan
