// SPDX-License-Identifier: BSD-3-Clause
// The Bezier surface and cut on random control points over a small bone (a coarse sphere, box or
// plate), with a random ROI and options (up to 4 relaxation rounds, schedules of up to 8 steps).
// Promises checked: no crash; on success the topology is kept, every coordinate is finite, only ROI
// vertices off its boundary move, unmoved vertices keep their coordinates bit for bit, and moved
// vertices lie on the surface.
#include "FuzzBytes.h"

#include "BezierCut/BezierCut.h"
#include "ROIExtract/ROIExtract.h"
#include "Support/FaceplanTestMeshes.h"

#include <cstdint>
#include <vector>

using namespace faceplan;
using faceplan::fuzz::FuzzBytes;
using faceplan::fuzz::Violation;

namespace {

const SurfaceMesh& Bone(int which) {
  // Coarse bones keep an execution cheap (the mapping's work grows with the moved vertices).
  static const SurfaceMesh sphere = testmesh::Icosphere(0, 10.0);
  static const SurfaceMesh box = testmesh::Box({-8, -6, -4}, {8, 6, 4}, 8.0);
  static const SurfaceMesh plate = testmesh::PlaneGrid(4, 4, -8, 8, -8, 8);
  return which == 0 ? sphere : which == 1 ? box : plate;
}

std::vector<Eigen::Vector3d> Curve(FuzzBytes& in, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& direction, bool special) {
  const int segments = in.range(1, 2);
  std::vector<Eigen::Vector3d> points(std::size_t(3 * segments + 1) + (in.byte() == 0 ? 1 : 0));
  for (std::size_t k = 0; k < points.size(); ++k) {
    points[k] = start + direction * (16.0 * double(k) / double(points.size() - 1));
    for (int c = 0; c < 3; ++c)
      points[k][c] += special ? in.number(4.0) : in.scaled(4.0);
  }
  return points;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzBytes in(data, size);
  const SurfaceMesh& bone = Bone(in.range(0, 2));
  const Eigen::Index n = bone.numPoints();

  // ROI: a ball around a vertex, optionally with random vertices toggled.
  std::vector<std::uint8_t> selected(std::size_t(n), 0);
  const Eigen::RowVector3d centre = bone.points.row(in.range(0, int(n) - 1));
  const double radius = 2.0 + 10.0 * (in.scaled(1.0) + 1.0);
  for (Eigen::Index i = 0; i < n; ++i)
    selected[std::size_t(i)] = (bone.points.row(i) - centre).norm() < radius;
  for (int toggles = in.range(0, 4); toggles > 0; --toggles)
    selected[std::size_t(in.range(0, int(n) - 1))] ^= 1;
  ROIResult roi;
  if (!ComputeROI(bone, selected, roi))
    Violation("the ROI of a valid mesh was refused");

  const bool special = in.byte() < 16;
  const Eigen::Vector3d start =
      centre.transpose() +
      Eigen::Vector3d(-8 + in.scaled(4.0), -8 + in.scaled(4.0), in.scaled(6.0));
  std::vector<Eigen::Vector3d> curveU = Curve(in, start, Eigen::Vector3d::UnitX(), special);
  std::vector<Eigen::Vector3d> curveV = Curve(in, start, Eigen::Vector3d::UnitY(), special);
  if (!in.flag())
    curveV.front() = curveU.front();

  BezierCutOptions options;
  options.operation = in.flag() ? CutOperation::Fill : CutOperation::Cut;
  options.flipNormal = in.flag();
  options.displayResolution = in.range(0, 6);
  options.localRepair = in.flag();
  options.stepSchedules = {in.range(0, 4)};
  if (in.flag())
    options.stepSchedules.push_back(in.range(1, 8));
  options.maxRelaxIterations = in.range(0, 4);

  BezierSurface surface;
  const bool created = BezierSurface::Create(curveU, curveV, options.flipNormal, surface).ok;
  if (created) {
    Eigen::Vector3d offset;
    offset << in.scaled(20.0), in.scaled(20.0), in.scaled(20.0); // sequenced reads
    const Eigen::Vector3d x = start + offset;
    const SurfaceProjection p = surface.project(x);
    if (!p.point.allFinite() || !std::isfinite(p.signedDistance) || p.u < 0 || p.u > 1 || p.v < 0 ||
        p.v > 1)
      Violation("a projection onto a valid surface is not finite or leaves [0,1]^2");
  }

  // A valid surface is cut onto directly (one Create per input: it is most of an execution); the
  // curves are given to the cut only when Create refused them, and the cut must refuse them too.
  CutMeshTopology topology;
  if (!PrepareCutMesh(bone, topology))
    Violation("a valid bone was refused");
  BezierCutResult result;
  const Status cut =
      created ? BezierCut(bone, topology, roi.mask, roi.boundary, surface, options, result)
              : BezierCut(bone, topology, roi.mask, roi.boundary, curveU, curveV, options, result);
  if (!cut) {
    if (cut.message.empty())
      Violation("a cut error without a message");
    return 0;
  }
  if (!created)
    Violation("the cut accepted control points that the surface refuses");
  if (result.points.rows() != n || result.displacement.rows() != n ||
      result.moved.size() != std::size_t(n))
    Violation("the cut changed the number of points");
  if (!result.points.allFinite() || !result.displacement.allFinite())
    Violation("the cut gave a non-finite coordinate");
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::size_t s = std::size_t(i);
    if (result.moved[s]) {
      if (!roi.mask[s] || roi.boundary[s])
        Violation("a vertex outside the ROI or on its boundary moved");
      const Eigen::Vector2d uv = result.parameters[s];
      const double off =
          (surface.evaluate(uv.x(), uv.y()) - result.points.row(i).transpose()).norm();
      if (!(off <= 1e-9 * surface.size()))
        Violation("a moved vertex is not on the surface");
    } else if (!(result.points.row(i) == bone.points.row(i)) ||
               !result.displacement.row(i).isZero(0.0)) {
      Violation("an unmoved vertex changed");
    }
  }
  return 0;
}
