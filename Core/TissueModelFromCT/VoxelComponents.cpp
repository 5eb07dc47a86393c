// SPDX-License-Identifier: BSD-3-Clause
#include "TissueModelFromCT/VoxelComponents.h"

#include <algorithm>
#include <vector>

namespace faceplan {

VoxelComponents FindComponents(const std::vector<std::uint8_t>& mask, const std::array<int, 3>& d) {
  VoxelComponents c;
  c.id.assign(mask.size(), -1);
  const long long sy = d[0], sz = (long long)d[0] * d[1];
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < mask.size(); ++seed) {
    if (!mask[seed] || c.id[seed] >= 0)
      continue;
    const int label = int(c.sizes.size());
    long long size = 0;
    bool border = false;
    c.id[seed] = label;
    stack.push_back(seed);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      ++size;
      const int i = int(v % d[0]), j = int((v / d[0]) % d[1]), k = int(v / sz);
      border =
          border || i == 0 || j == 0 || k == 0 || i + 1 == d[0] || j + 1 == d[1] || k + 1 == d[2];
      const long long steps[6] = {-1, 1, -sy, sy, -sz, sz};
      const bool inside[6] = {i > 0, i + 1 < d[0], j > 0, j + 1 < d[1], k > 0, k + 1 < d[2]};
      for (int n = 0; n < 6; ++n) {
        if (!inside[n])
          continue;
        const std::size_t w = std::size_t((long long)v + steps[n]);
        if (mask[w] && c.id[w] < 0) {
          c.id[w] = label;
          stack.push_back(w);
        }
      }
    }
    c.sizes.push_back(size);
    c.touchesBorder.push_back(border);
  }
  return c;
}

void KeepLargestComponent(std::vector<std::uint8_t>& mask, const std::array<int, 3>& dims) {
  const VoxelComponents c = FindComponents(mask, dims);
  if (c.sizes.size() < 2)
    return;
  const int largest = int(std::max_element(c.sizes.begin(), c.sizes.end()) - c.sizes.begin());
  for (std::size_t v = 0; v < mask.size(); ++v)
    if (c.id[v] != largest)
      mask[v] = 0;
}

} // namespace faceplan
