// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Triangle intersection predicates for BezierCut: which triangles of a surface mesh cross each
// other after its points moved, found through a uniform spatial hash. Cells are fan-triangulated.
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <unsupported/Eigen/BVH>

#include <cstdint>
#include <vector>

namespace faceplan {

struct Tri {
  std::int64_t v[3];
};

// The fan triangulation (0, k, k+1) of every cell with three or more points.
std::vector<Tri> FanTriangles(const SurfaceMesh& mesh);

// Do triangles A and B (points P) cross? Pairs sharing two or more vertices are never reported
// (their folding is a flip); skipSharedVertex also skips pairs sharing one vertex. Touching along
// an edge or at a vertex does not count.
bool TrianglesIntersect(const Tri& A, const Tri& B, const RowVectors3d& P, bool skipSharedVertex);

// True when the triangles' bounding boxes are apart by more than 1e-6 of the larger box: such a
// pair cannot cross (TrianglesIntersect reports a crossing only for points within 1e-9 of the
// pair's size of the other triangle, far inside this margin), so the exact test can be skipped.
bool TriangleBoxesApart(const Tri& A, const Tri& B, const RowVectors3d& P);

// Bounding-volume tree (Eigen's KdBVH) over the boxes of some triangles. Unlike a uniform grid it
// does not degrade when triangle sizes or aspect ratios vary (a stretched Bezier patch, a large
// osteotomy cap beside a fine mesh), and it never drops a triangle however large.
class TriangleBoxTree {
public:
  TriangleBoxTree(const std::vector<Tri>& tris, const RowVectors3d& P,
                  const std::vector<std::int64_t>& ids);
  // The triangles among `ids` that TriangleBoxesApart may not rule out against triangle t: every
  // one whose box, grown by 1e-6 of its largest extent, meets t's box grown the same way (a
  // superset of the pairs not apart, sorted, unique, t itself included when it is among ids).
  void candidates(std::int64_t t, std::vector<std::int64_t>& out) const;

private:
  using Box = Eigen::AlignedBox<double, 3>;
  Box grownBox(std::int64_t t) const;
  const std::vector<Tri>& tris_;
  const RowVectors3d& points_;
  std::vector<std::int64_t> ids_;
  std::vector<Box> boxes_; // grownBox of ids_[k]
  Eigen::KdBVH<double, 3, int> tree_;
};

// Triangles (among those flagged in activeTri) that intersect another triangle in `after` but did
// not in `before`, tested against all triangles near the active region.
std::vector<std::int64_t> NewIntersections(const std::vector<Tri>& tris, const RowVectors3d& before,
                                           const RowVectors3d& after,
                                           const std::vector<std::uint8_t>& activeTri);

// The same over the fan triangulation of `cells`, for the triangles with a point flagged in
// `active`; returns how many, and the first one's index in *firstTriangle (-1: none).
std::int64_t CountNewIntersections(const SurfaceMesh& cells, const RowVectors3d& before,
                                   const RowVectors3d& after,
                                   const std::vector<std::uint8_t>& active,
                                   std::int64_t* firstTriangle = nullptr);

} // namespace faceplan
