// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A tiny VTK-free reader of the VTK XML UnstructuredGrid files in Data/ (inline data, format
// "ascii" or "binary", raw or vtkZLibDataCompressor, UInt32 or UInt64 headers, little endian),
// enough for the report to load tetrahedral meshes and their point arrays. Not a general VTK
// reader: no appended data, no big-endian files, only VTK_TETRA cells are accepted.
#include "Mesh/TetMesh.h"

#include <map>
#include <string>
#include <vector>

namespace faceplan::bench {

struct VtuMesh {
  TetMesh mesh;
  std::map<std::string, std::vector<double>> pointData; // one value per point (first component)
};

// False with `error` set when the file cannot be read or holds other cells than tetrahedra.
bool ReadVtuTets(const std::string& path, VtuMesh& out, std::string& error);

} // namespace faceplan::bench
