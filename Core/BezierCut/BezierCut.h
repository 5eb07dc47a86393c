// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Bezier cut / fill of a bone surface (no VTK).
//
// The operative surface S(u,v) and its normal n are BezierSurface's (BezierSurface.h).
//
// Side of a vertex x: let (u*,v*) minimise |S(u,v) - x| over [0,1]^2 (grid initialisation, then
// projected Newton). The vertex "projects inside the patch" when S(u*,v*) is an orthogonal foot
// point, i.e. x - S(u*,v*) has no tangential component (up to 1e-6 of the surface size plus 1e-4
// of the distance); vertices whose closest patch point lies on the patch border with a tangential
// residual project outside and never move. Its signed distance is d = (x - S(u*,v*)) . n^(u*,v*);
// d > 0 is the side n points to.
//
// Cut: ROI vertices that are not ROIBoundary, project inside and have d > 0 move onto S.
// Fill: the same with d < 0. Every other vertex keeps its coordinates bit for bit.
//
// Guarantees on success: the topology is the input's (only coordinates change); every moved vertex
// lies on S (it is S(u,v) evaluated at its final parameters); no triangle touching a moved vertex
// is degenerate or flipped, and no pair of triangles intersects that did not intersect before.
// "Flipped": a triangle with a vertex that did not move must keep the sign of its normal relative
// to its original normal; a triangle whose vertices all moved lies in S and must face the way the
// moved region faced (sign of sum over those triangles of original area vector . n), which for a
// triangle that originally faced n is the same as keeping its normal's sign.
// Polygons with more than 3 points are checked through a fan triangulation.
//
// Where direct projection would fold or collapse triangles, the moved vertices are relaxed
// tangentially within S (only their (u,v) change, so they stay on S), in this order until the
// full check passes:
//  1. local repair on S: untangling (each vertex of a flipped/degenerate triangle, then also its
//     moved neighbours, moves by a pattern search in (u,v) to maximise the smallest signed size of
//     its triangles), then harmonic (uniform Tutte) relaxation of neighbourhoods of the bad
//     triangles that double their ring count each round, each followed by untangling;
//  2. intermediary surfaces as in the ICAT 2008 paper: at step t = s/T (s = 1..T) vertex i sits at
//     (1-t) x_i + t S(u_i,v_i); after each step the vertices near triangles that flipped relative
//     to the previous step, degenerated or became badly squashed are relaxed harmonically, and at
//     t = 1 the full check (flips and new intersections, the latter through a uniform spatial
//     hash over the moved neighbourhood) must pass. Schedules with more steps are tried in turn.
// If all fail, an error is returned (naming ROIBoundary vertices that lie beyond the surface, the
// usual cause), never a bad mesh.
#include "BezierCut/BezierSurface.h"
#include "BezierCut/MeshIntersection.h"
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace faceplan {

enum class CutOperation { Cut = 0, Fill = 1 };

struct BezierCutOptions {
  CutOperation operation = CutOperation::Cut;
  bool flipNormal = false;
  int displayResolution = 16; // tessellation intervals per Bezier segment (output port 1)
  bool localRepair = true;    // step 1 of the fallback (off: intermediary surfaces only)
  std::vector<int> stepSchedules = {8, 32}; // numbers of intermediary surfaces tried in turn
  int maxRelaxIterations =
      24; // relaxation rounds per step (the region doubles its rings each round)
};

struct BezierCutResult {
  RowVectors3d points;       // n x 3: the new coordinates
  RowVectors3d displacement; // n x 3: points - input points (exactly zero where unmoved)
  std::vector<std::uint8_t> moved;
  std::vector<Eigen::Vector2d> parameters; // (u,v) of each moved vertex (others: 0)
  std::int64_t numMoved = 0;
  std::int64_t numInsidePatch = 0; // ROI vertices projecting inside the patch
  int intermediarySteps = 0;       // 0: direct projection was valid; 1: local repair on S;
                                   // T > 1: mapped through T intermediary surfaces
  double maxDistanceToSurface = 0; // max over moved vertices of |x - S(u,v)| (should be ~1e-15)
  SurfaceMesh operativeSurface;    // triangles of S for display
  RowVectors3d operativeNormals;   // unit normal (flip applied) at each operativeSurface point
  std::vector<Eigen::Vector2d> operativeParameters; // (u,v) of each operativeSurface point
  std::string mappingNote;           // why intermediary surfaces were needed (informational)
  std::vector<std::string> warnings; // e.g. nothing moved
};

// What BezierCut derives from the bone surface alone, whatever the control points: each point's
// edge neighbours and the fan triangulation of the cells. A caller that cuts the same bone again
// and again (the filter while control points are dragged) builds it once with PrepareCutMesh.
struct CutMeshTopology {
  std::vector<std::vector<std::int64_t>> neighbours; // sorted, unique, per point
  std::vector<Tri> triangles;                        // FanTriangles(mesh)
};

// Validates mesh as BezierCut does and builds its topology (left empty on failure).
Status PrepareCutMesh(const SurfaceMesh& mesh, CutMeshTopology& topology);

// mesh: the bone surface; roiMask / roiBoundary: one entry per point (see ROIExtract.h).
// On failure `result` is left empty and the message says which control point/surface problem or
// mapping problem occurred.
Status BezierCut(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary,
                 const std::vector<Eigen::Vector3d>& curveU,
                 const std::vector<Eigen::Vector3d>& curveV, const BezierCutOptions& options,
                 BezierCutResult& result);

// The same cut with topology = PrepareCutMesh(mesh) built earlier for this very mesh (a topology
// whose sizes do not fit the mesh is an error).
Status BezierCut(const SurfaceMesh& mesh, const CutMeshTopology& topology,
                 const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary,
                 const std::vector<Eigen::Vector3d>& curveU,
                 const std::vector<Eigen::Vector3d>& curveV, const BezierCutOptions& options,
                 BezierCutResult& result);

// The same cut onto a surface already made by BezierSurface::Create, for callers that check or
// reuse the surface themselves. The surface's own orientation is used (options.flipNormal is not
// read); a default-constructed surface is an error.
Status BezierCut(const SurfaceMesh& mesh, const CutMeshTopology& topology,
                 const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary, const BezierSurface& surface,
                 const BezierCutOptions& options, BezierCutResult& result);

} // namespace faceplan
