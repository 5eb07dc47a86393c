// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Maps the vertices BezierCut moves onto its surface without folding the mesh: direct projection,
// then local repair on S, then intermediary surfaces (the fallback order BezierCut.h describes).
#include "BezierCut/BezierSurface.h"
#include "BezierCut/MeshIntersection.h"
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace faceplan {

struct CutMappingOptions {
  bool localRepair = true;
  std::vector<int> stepSchedules;
  int maxRelaxIterations = 24;
};

struct CutMapping {
  bool ok = false;
  RowVectors3d points;                     // all points; moved ones on S
  std::vector<Eigen::Vector2d> parameters; // (u,v) of each moved point
  int intermediarySteps = 0;               // 0: direct, 1: local repair on S, T > 1: T surfaces
  std::string directProblem;               // why direct projection failed (empty if it did not)
  std::string problem;                     // why the last attempt failed (when !ok)
  std::int64_t repairVertexSearches = 0;   // pattern searches of one vertex in the local repair
};

// triangles: FanTriangles(mesh); neighbours: the sorted edge neighbours of each point; moved: the
// points to map; footParameters: the (u,v) of each ROI point's projection onto S (the unmoved ones
// give the boundary values).
CutMapping MapCutOntoSurface(const BezierSurface& surface, const SurfaceMesh& mesh,
                             const std::vector<Tri>& triangles,
                             const std::vector<std::vector<std::int64_t>>& neighbours,
                             const std::vector<std::uint8_t>& moved,
                             const std::vector<Eigen::Vector2d>& footParameters,
                             const CutMappingOptions& options);

} // namespace faceplan
