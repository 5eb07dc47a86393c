#pragma once
// Triangle intersection predicates for BezierCut: which triangles of a surface mesh cross each
// other after its points moved, found through a uniform spatial hash. Cells are fan-triangulated.
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>

#include <cstdint>
#include <unordered_map>
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

// Uniform spatial hash over triangle bounding boxes.
class TriangleHash {
public:
  TriangleHash(const std::vector<Tri>& tris, const RowVectors3d& P,
               const std::vector<std::int64_t>& ids, double cell);
  // Candidate triangles whose cells overlap those of triangle t (sorted, unique).
  void Candidates(std::int64_t t, std::vector<std::int64_t>& out) const;

private:
  void Range(std::int64_t t, Eigen::Array3i& lo, Eigen::Array3i& hi) const;
  static std::int64_t Key(int x, int y, int z);
  const std::vector<Tri>& tris_;
  const RowVectors3d& P_;
  double h_;
  std::unordered_map<std::int64_t, std::vector<std::int64_t>> map_;
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
