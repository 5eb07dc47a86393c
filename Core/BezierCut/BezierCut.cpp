// SPDX-License-Identifier: BSD-3-Clause
#include "BezierCut/BezierCut.h"

#include "BezierCut/CutMapping.h"
#include "BezierCut/MessageFormat.h"
#include "ROIExtract/ROIExtract.h"

#include <algorithm>
#include <cmath>

namespace faceplan {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// The sorted, unique edge neighbours of every point (cells of two or more points).
std::vector<std::vector<std::int64_t>> EdgeNeighbours(const SurfaceMesh& mesh) {
  std::vector<std::vector<std::int64_t>> nbrs(mesh.numPoints());
  auto addEdge = [&](std::int64_t a, std::int64_t b) {
    if (a == b)
      return;
    nbrs[a].push_back(b);
    nbrs[b].push_back(a);
  };
  for (std::int64_t c = 0; c < mesh.numCells(); ++c) {
    const std::int64_t m = mesh.cellSize(c);
    const std::int64_t* ids = mesh.cell(c);
    if (m == 2)
      addEdge(ids[0], ids[1]);
    else if (m >= 3)
      for (std::int64_t k = 0; k < m; ++k)
        addEdge(ids[k], ids[(k + 1) % m]);
  }
  for (auto& nb : nbrs) {
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
  }
  return nbrs;
}

} // namespace

Status PrepareCutMesh(const SurfaceMesh& mesh, CutMeshTopology& topology) {
  topology = CutMeshTopology{};
  const Status s = ValidateSurfaceMesh(mesh);
  if (!s)
    return s;
  topology.neighbours = EdgeNeighbours(mesh);
  topology.triangles = FanTriangles(mesh);
  return Status::Ok();
}

Status BezierCut(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary, const std::vector<Vector3d>& curveU,
                 const std::vector<Vector3d>& curveV, const BezierCutOptions& options,
                 BezierCutResult& result) {
  result = BezierCutResult{};
  CutMeshTopology topology;
  const Status s = PrepareCutMesh(mesh, topology);
  if (!s)
    return s;
  return BezierCut(mesh, topology, roiMask, roiBoundary, curveU, curveV, options, result);
}

namespace {

// The checks both BezierCut overloads make before the surface is used.
Status ValidateCutInputs(const SurfaceMesh& mesh, const CutMeshTopology& topology,
                         const std::vector<std::uint8_t>& roiMask,
                         const std::vector<std::uint8_t>& roiBoundary) {
  Status s = ValidateSurfaceMesh(mesh);
  if (!s)
    return s;
  const std::int64_t n = mesh.numPoints();
  std::int64_t fanTriangles = 0;
  for (std::int64_t c = 0; c < mesh.numCells(); ++c)
    fanTriangles += std::max<std::int64_t>(mesh.cellSize(c) - 2, 0);
  if (std::int64_t(topology.neighbours.size()) != n ||
      std::int64_t(topology.triangles.size()) != fanTriangles)
    return Status::Error(
        "the prepared cut topology (" + std::to_string(topology.neighbours.size()) + " points, " +
        std::to_string(topology.triangles.size()) + " triangles) does not belong to this mesh (" +
        std::to_string(n) + " points, " + std::to_string(fanTriangles) + " triangles)");
  if (std::int64_t(roiMask.size()) != n || std::int64_t(roiBoundary.size()) != n)
    return Status::Error("ROIMask and ROIBoundary need one entry per point (" + std::to_string(n) +
                         "), got " + std::to_string(roiMask.size()) + " and " +
                         std::to_string(roiBoundary.size()));
  return Status::Ok();
}

// The cut itself, once the inputs are checked and the surface made.
Status CutOntoSurface(const SurfaceMesh& mesh, const CutMeshTopology& topology,
                      const std::vector<std::uint8_t>& roiMask,
                      const std::vector<std::uint8_t>& roiBoundary, const BezierSurface& surf,
                      const BezierCutOptions& options, BezierCutResult& result) {
  const std::int64_t n = mesh.numPoints();
  std::int64_t numROI = 0;
  for (std::int64_t i = 0; i < n; ++i)
    numROI += roiMask[i] ? 1 : 0;
  if (numROI == 0)
    return Status::Error("the ROI is empty (ROIMask is 0 everywhere)");

  std::vector<std::uint8_t> moved(n, 0);
  std::vector<Vector2d> foot(n, Vector2d::Zero());
  std::int64_t inside = 0;
  std::vector<std::int64_t> boundaryOnSide; // ROIBoundary vertices beyond the surface (never move)
  for (std::int64_t i = 0; i < n; ++i) {
    if (!roiMask[i])
      continue;
    const SurfaceProjection pr = surf.project(mesh.points.row(i).transpose());
    foot[i] = Vector2d(pr.u, pr.v); // also for unmoved ROI vertices: relaxation boundary values
    if (!pr.inside)
      continue;
    ++inside;
    const bool side =
        options.operation == CutOperation::Cut ? pr.signedDistance > 0 : pr.signedDistance < 0;
    if (side && !roiBoundary[i])
      moved[i] = 1;
    if (side && roiBoundary[i] && std::abs(pr.signedDistance) > 1e-9 * surf.size())
      boundaryOnSide.push_back(i);
  }
  if (inside == 0)
    return Status::Error("surface not meeting the ROI: no ROI vertex projects inside the (u,v) "
                         "patch [0,1]^2 of the Bezier surface");

  BezierCutResult r;
  r.numInsidePatch = inside;
  surf.tessellate(options.displayResolution, r.operativeSurface, &r.operativeParameters,
                  &r.operativeNormals);
  r.moved = moved;
  for (std::int64_t i = 0; i < n; ++i)
    r.numMoved += moved[i];
  r.points = mesh.points;
  r.displacement = RowVectors3d::Zero(n, 3);
  r.parameters.assign(n, Vector2d::Zero());
  if (r.numMoved == 0) {
    r.warnings.push_back(std::string("no ROI vertex lies on the ") +
                         (options.operation == CutOperation::Cut
                              ? "cut (normal) side"
                              : "fill side (against the normal)") +
                         " inside the patch: nothing moved");
    result = std::move(r);
    return Status::Ok();
  }

  const std::vector<std::vector<std::int64_t>>& nbrs = topology.neighbours;
  CutMappingOptions mappingOptions;
  mappingOptions.localRepair = options.localRepair;
  mappingOptions.stepSchedules = options.stepSchedules;
  mappingOptions.maxRelaxIterations = options.maxRelaxIterations;
  const CutMapping mapping =
      MapCutOntoSurface(surf, mesh, topology.triangles, nbrs, moved, foot, mappingOptions);
  r.intermediarySteps = mapping.intermediarySteps;
  if (!mapping.ok) {
    std::string hint = "Try a smaller cut, a larger ROI, a finer mesh or a smoother surface";
    std::int64_t nearMoved = 0, example = -1;
    for (std::int64_t b : boundaryOnSide)
      for (std::int64_t j : nbrs[b])
        if (moved[j]) {
          ++nearMoved;
          if (example < 0)
            example = b;
          break;
        }
    if (nearMoved > 0)
      hint = std::to_string(nearMoved) + " ROIBoundary vertices (which never move) lie on the " +
             (options.operation == CutOperation::Cut ? "cut" : "fill") +
             " side next to moved vertices (e.g. vertex " + std::to_string(example) + " at " +
             FormatPoint(mesh.points.row(example).transpose()) +
             "): enlarge the ROI so that its boundary stays on the other side of the surface";
    return Status::Error(
        "the cut could not be mapped onto the surface without folding the mesh: direct "
        "projection gave " +
        mapping.directProblem + "; after the intermediary surfaces " + mapping.problem + ". " +
        hint);
  }

  const RowVectors3d& P = mapping.points;
  const std::vector<Vector2d>& uv = mapping.parameters;
  for (std::int64_t i = 0; i < n; ++i) {
    if (!moved[i])
      continue;
    r.points.row(i) = P.row(i);
    r.displacement.row(i) = P.row(i) - mesh.points.row(i);
    r.parameters[i] = uv[i];
    r.maxDistanceToSurface =
        std::max(r.maxDistanceToSurface,
                 (P.row(i).transpose() - surf.evaluate(uv[i].x(), uv[i].y())).norm());
  }
  if (r.intermediarySteps > 0)
    r.mappingNote = "direct projection would fold the mesh (" + mapping.directProblem + ")";
  result = std::move(r);
  return Status::Ok();
}

} // namespace

Status BezierCut(const SurfaceMesh& mesh, const CutMeshTopology& topology,
                 const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary, const std::vector<Vector3d>& curveU,
                 const std::vector<Vector3d>& curveV, const BezierCutOptions& options,
                 BezierCutResult& result) {
  result = BezierCutResult{};
  Status s = ValidateCutInputs(mesh, topology, roiMask, roiBoundary);
  if (!s)
    return s;
  BezierSurface surf;
  s = BezierSurface::Create(curveU, curveV, options.flipNormal, surf);
  if (!s)
    return s;
  return CutOntoSurface(mesh, topology, roiMask, roiBoundary, surf, options, result);
}

Status BezierCut(const SurfaceMesh& mesh, const CutMeshTopology& topology,
                 const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary, const BezierSurface& surface,
                 const BezierCutOptions& options, BezierCutResult& result) {
  result = BezierCutResult{};
  const Status s = ValidateCutInputs(mesh, topology, roiMask, roiBoundary);
  if (!s)
    return s;
  if (!(surface.size() > 0))
    return Status::Error("no surface: make it with BezierSurface::Create first");
  return CutOntoSurface(mesh, topology, roiMask, roiBoundary, surface, options, result);
}

} // namespace faceplan
