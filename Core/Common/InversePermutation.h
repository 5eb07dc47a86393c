// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <vector>

namespace faceplan {

// position[perm[k]] = k: where each index of an ordering went (orderings here are new -> old, as
// CHOLMOD's Perm and METIS's are, so this is old -> new).
inline std::vector<int> InversePermutation(const int* perm, int n) {
  std::vector<int> position(n);
  for (int k = 0; k < n; ++k)
    position[perm[k]] = k;
  return position;
}

inline std::vector<int> InversePermutation(const std::vector<int>& perm) {
  return InversePermutation(perm.data(), static_cast<int>(perm.size()));
}

} // namespace faceplan
