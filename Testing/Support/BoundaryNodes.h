// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The benchmarks' and the report's node sets keep the tissue's outer surface: its nodes are those
// of faces used by a single tetrahedron.
#include "Mesh/TetMesh.h"

#include <vector>

namespace faceplan::bench {

// One entry per mesh point: 1 on a face that a single tetrahedron uses, else 0.
std::vector<char> BoundaryNodes(const TetMesh& mesh);

} // namespace faceplan::bench
