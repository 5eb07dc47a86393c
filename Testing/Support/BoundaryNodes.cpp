// SPDX-License-Identifier: BSD-3-Clause
#include "Support/BoundaryNodes.h"

#include <algorithm>
#include <array>

namespace faceplan::bench {

std::vector<char> BoundaryNodes(const TetMesh& mesh) {
  // One sort over every cell's faces: a face listed once is on the boundary.
  std::vector<std::array<int, 3>> faces;
  faces.reserve(4 * static_cast<size_t>(mesh.numTets()));
  static const int f[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (const auto& face : f) {
      std::array<int, 3> key = {mesh.tets(e, face[0]), mesh.tets(e, face[1]),
                                mesh.tets(e, face[2])};
      std::sort(key.begin(), key.end());
      faces.push_back(key);
    }
  std::sort(faces.begin(), faces.end());
  std::vector<char> boundary(mesh.numPoints(), 0);
  for (size_t i = 0; i < faces.size();) {
    size_t k = i + 1;
    while (k < faces.size() && faces[k] == faces[i])
      ++k;
    if (k - i == 1)
      for (int v : faces[i])
        boundary[v] = 1;
    i = k;
  }
  return boundary;
}

} // namespace faceplan::bench
