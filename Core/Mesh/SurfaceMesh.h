// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A polygonal surface as Core sees it (no VTK): points and polygon cells as plain arrays.
#include "Common/RowVectors3d.h"

#include <Eigen/Core>

#include <cstdint>
#include <initializer_list>
#include <vector>

namespace faceplan {

// Cells in compressed form (like vtkCellArray): cell c uses the point ids
// connectivity[offsets[c] .. offsets[c+1]). offsets has numCells()+1 entries, offsets[0] == 0.
// A cell of n >= 3 points is a polygon with the edges (p0,p1), ..., (p_{n-1},p0);
// a cell of 2 points is one edge; a cell of 1 point has no edge.
struct SurfaceMesh {
  RowVectors3d points;               // n x 3
  std::vector<std::int64_t> offsets; // numCells + 1
  std::vector<std::int64_t> connectivity;

  Eigen::Index numPoints() const { return points.rows(); }
  std::int64_t numCells() const { return offsets.empty() ? 0 : std::int64_t(offsets.size()) - 1; }
  std::int64_t cellSize(std::int64_t c) const { return offsets[c + 1] - offsets[c]; }
  const std::int64_t* cell(std::int64_t c) const { return connectivity.data() + offsets[c]; }

  // Appends one cell.
  void addCell(std::initializer_list<std::int64_t> ids) {
    if (offsets.empty())
      offsets.push_back(0);
    connectivity.insert(connectivity.end(), ids.begin(), ids.end());
    offsets.push_back(std::int64_t(connectivity.size()));
  }
};

} // namespace faceplan
