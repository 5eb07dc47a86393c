// SPDX-License-Identifier: BSD-3-Clause
// The contact mapping of CondensedFEMDeform (tissue boundary node -> closest point of the
// undeformed bone) on small random bones: triangles mostly, with quads, polygons, strips, lines
// and vertices mixed in, repeated point ids, optional ROIMask, SegmentId and Sliding, coordinates
// near the origin, offset by 2^20 or scaled up to the largest doubles. Only bones that the filter's
// own ValidateBone accepts reach the mapping, as in the filter. Promises checked: no crash; the map
// is consistent (sizes, offsets, ids in range, finite weights summing to 1); on bones of
// triangles, lines and vertices, a node is tied to a point within ContactDistance and no farther
// than the closest point an exact linear scan finds, and left untied only when the scan finds
// nothing within ContactDistance; a cut edit (points and Displacement moved together) keeps the
// contact (BoneInput) and, like a connectivity change, gives through the filter's cache the map
// that a fresh build gives; the node sets and
// movable displacements derived from the map are consistent and finite.
#include "FuzzBytes.h"

#include "CondensedFEMDeformBoneInput.h"
#include "CondensedFEMDeformContact.h"
#include "CondensedFEMDeformValidate.h"
#include "FacePlanUndeformedBone.h"

#include <Eigen/Geometry>

#include "vtkCell.h"
#include "vtkCellArray.h"
#include "vtkCellType.h"
#include "vtkDoubleArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

using namespace faceplan;
using namespace faceplan::fem_filter;
using faceplan::fuzz::FuzzBytes;
using faceplan::fuzz::Violation;

namespace {

// Coordinates are multiples of 1/16 (times a power of two), so a point plus a displacement minus
// that displacement is the point again, bit for bit: a cut edit leaves the undeformed bone exact.
double Grid(FuzzBytes& in, double scale) {
  return scale * double(int(in.byte()) - 128) / 16.0;
}

struct Bone {
  vtkSmartPointer<vtkPolyData> data;
  bool planarCellsOnly = true; // triangles, lines and vertices: interpolation reproduces points
};

Bone MakeBone(FuzzBytes& in, double scale, double offset) {
  Bone bone;
  bone.data = vtkSmartPointer<vtkPolyData>::New();
  const int n = in.range(1, 10);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (int i = 0; i < n; ++i) {
    const double x = offset + Grid(in, scale), y = offset + Grid(in, scale),
                 z = offset + Grid(in, scale);
    points->InsertNextPoint(x, y, z);
  }
  bone.data->SetPoints(points);
  vtkNew<vtkCellArray> verts, lines, polys, strips;
  const bool wildIds = in.byte() < 8; // ids the validation must refuse
  for (int c = in.range(0, 8); c >= 0; --c) {
    const int kind = in.byte() % 16;
    int count = 3, type = VTK_TRIANGLE;
    vtkCellArray* target = polys;
    if (kind == 10) {
      count = 1, target = verts;
    } else if (kind == 11) {
      count = 2, target = lines;
    } else if (kind == 12) {
      count = 4, type = VTK_QUAD;
    } else if (kind == 13) {
      count = in.range(3, 6), type = VTK_POLYGON;
    } else if (kind == 14) {
      count = in.range(3, 6), target = strips;
    }
    if (type != VTK_TRIANGLE || target != polys)
      bone.planarCellsOnly = bone.planarCellsOnly && (target == verts || target == lines);
    std::vector<vtkIdType> ids(static_cast<std::size_t>(count));
    for (vtkIdType& id : ids)
      id = wildIds ? in.range(-2, n + 1) : in.range(0, n - 1);
    target->InsertNextCell(vtkIdType(ids.size()), ids.data());
  }
  bone.data->SetVerts(verts);
  bone.data->SetLines(lines);
  bone.data->SetPolys(polys);
  bone.data->SetStrips(strips);

  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  displacement->SetNumberOfTuples(n + (in.byte() < 4 ? 1 : 0));
  for (vtkIdType i = 0; i < displacement->GetNumberOfTuples(); ++i)
    for (int c = 0; c < 3; ++c)
      displacement->SetComponent(i, c, in.flag() ? Grid(in, scale) / 4.0 : 0.0);
  bone.data->GetPointData()->AddArray(displacement);
  if (in.flag()) {
    vtkNew<vtkDoubleArray> mask;
    mask->SetName("ROIMask");
    mask->SetNumberOfTuples(n);
    for (int i = 0; i < n; ++i)
      mask->SetValue(i, double(in.byte() % 3) * 0.5);
    bone.data->GetPointData()->AddArray(mask);
  }
  if (in.flag()) {
    vtkNew<vtkDoubleArray> segments;
    segments->SetName("SegmentId");
    segments->SetNumberOfTuples(n);
    for (int i = 0; i < n; ++i)
      segments->SetValue(i, double(in.byte() % 3));
    bone.data->GetPointData()->AddArray(segments);
  }
  if (in.flag()) {
    vtkNew<vtkDoubleArray> sliding;
    sliding->SetName("Sliding");
    sliding->SetNumberOfTuples(n);
    for (int i = 0; i < n; ++i)
      sliding->SetValue(i, double(in.byte() & 1));
    bone.data->GetPointData()->AddArray(sliding);
  }
  return bone;
}

// The bone before its Displacement, as the contact defines it (the filter's own helper).
vtkSmartPointer<vtkPolyData> Undeformed(vtkPolyData* bone) {
  std::vector<double> points;
  UndeformedPoints(bone, bone->GetPointData()->GetArray("Displacement"), points);
  return vtkPolyData::SafeDownCast(UndeformedBone(bone, points));
}

using Eigen::Vector3d;

// The closest point to x on triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
Vector3d ClosestOnTriangle(const Vector3d& x, const Vector3d& a, const Vector3d& b,
                           const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ax = x - a;
  const double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0 && d2 <= 0)
    return a;
  const Vector3d bx = x - b;
  const double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0 && d4 <= d3)
    return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
    return a + ab * (d1 / (d1 - d3));
  const Vector3d cx = x - c;
  const double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0 && d5 <= d6)
    return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
    return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denominator = 1.0 / (va + vb + vc);
  return a + ab * (vb * denominator) + ac * (vc * denominator);
}

double SegmentDistance(const Vector3d& x, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - x).norm();
}

// The smallest exact distance from x to the bone's vertices, lines of non-zero length and
// triangles of non-zero area (VTK's cells skip degenerate ones), by a linear scan; the locator's
// oracle for bones of triangles, lines and vertices only.
double ScanDistance(vtkPolyData* undeformed, const double xIn[3]) {
  const Vector3d x(xIn[0], xIn[1], xIn[2]);
  vtkNew<vtkIdList> ids;
  auto point = [&](vtkIdType k) {
    double p[3];
    undeformed->GetPoint(ids->GetId(k), p);
    return Vector3d(p[0], p[1], p[2]);
  };
  double best = std::numeric_limits<double>::infinity();
  for (vtkIdType c = 0; c < undeformed->GetNumberOfCells(); ++c) {
    undeformed->GetCellPoints(c, ids);
    const int type = undeformed->GetCellType(c);
    if (type == VTK_VERTEX) {
      best = std::min(best, (point(0) - x).norm());
    } else if (type == VTK_LINE) {
      const Vector3d a = point(0), b = point(1);
      if ((b - a).norm() > 1e-12 * a.norm())
        best = std::min(best, SegmentDistance(x, a, b));
    } else if (type == VTK_TRIANGLE) {
      const Vector3d a = point(0), b = point(1), c3 = point(2);
      const double scale = std::max({(b - a).squaredNorm(), (c3 - a).squaredNorm(), 1e-300});
      if ((b - a).cross(c3 - a).norm() > 1e-9 * scale)
        best = std::min(best, (ClosestOnTriangle(x, a, b, c3) - x).norm());
    }
  }
  return best;
}

bool SameMap(const ContactMap& a, const ContactMap& b) {
  if (a.tiedNodes != b.tiedNodes || a.weightStart != b.weightStart ||
      a.bonePointIds != b.bonePointIds || a.movable != b.movable ||
      a.nearestBonePoint != b.nearestBonePoint || a.released != b.released ||
      a.weights.size() != b.weights.size() || a.normals.size() != b.normals.size())
    return false;
  for (std::size_t k = 0; k < a.weights.size(); ++k)
    if (!(std::abs(a.weights[k] - b.weights[k]) <= 1e-12))
      return false;
  for (std::size_t k = 0; k < a.normals.size(); ++k)
    if (!(std::abs(a.normals[k] - b.normals[k]) <= 1e-12))
      return false;
  return true;
}

void CheckMap(const ContactMap& map, vtkUnstructuredGrid* tissue,
              const std::vector<vtkIdType>& boundary, const Bone& bone, double distance,
              double size) {
  const std::size_t tied = map.tiedNodes.size();
  const vtkIdType n = bone.data->GetNumberOfPoints();
  if (map.weightStart.size() != tied + 1 || map.movable.size() != tied ||
      map.nearestBonePoint.size() != tied || map.released.size() != tied ||
      map.normals.size() != 3 * tied || map.weightStart.front() != 0 ||
      std::size_t(map.weightStart.back()) != map.weights.size() ||
      map.bonePointIds.size() != map.weights.size())
    Violation("contact map arrays of inconsistent sizes");
  for (std::size_t t = 0; t < tied; ++t)
    if (map.weightStart[t + 1] <= map.weightStart[t])
      Violation("a tied node without bone points");
  for (vtkIdType id : map.bonePointIds)
    if (id < 0 || id >= n)
      Violation("a bone point id out of range");
  for (vtkIdType id : map.nearestBonePoint)
    if (id < 0 || id >= n)
      Violation("a nearest bone point out of range");
  for (double v : map.normals)
    if (!std::isfinite(v))
      Violation("a non-finite contact normal");

  vtkSmartPointer<vtkPolyData> undeformed = Undeformed(bone.data);
  const double slack = 1e-9 * (size + distance) + 1e-300;
  std::size_t t = 0;
  for (vtkIdType node : boundary) {
    const bool isTied = t < tied && map.tiedNodes[t] == node;
    double x[3];
    tissue->GetPoint(node, x);
    if (!isTied) {
      // Nodes at the threshold (to round-off) may go either way.
      if (bone.planarCellsOnly && ScanDistance(undeformed, x) < distance - slack)
        Violation("a node within ContactDistance left untied");
      continue;
    }
    double sum = 0.0, p[3] = {0.0, 0.0, 0.0};
    for (vtkIdType k = map.weightStart[t]; k < map.weightStart[t + 1]; ++k) {
      const double w = map.weights[std::size_t(k)];
      if (!std::isfinite(w))
        Violation("a non-finite contact weight");
      sum += w;
      double q[3];
      undeformed->GetPoint(map.bonePointIds[std::size_t(k)], q);
      for (int c = 0; c < 3; ++c)
        p[c] += w * q[c];
    }
    if (!(std::abs(sum - 1.0) <= 1e-6))
      Violation("contact weights do not sum to 1");
    if (bone.planarCellsOnly) {
      const double d = std::sqrt((p[0] - x[0]) * (p[0] - x[0]) + (p[1] - x[1]) * (p[1] - x[1]) +
                                 (p[2] - x[2]) * (p[2] - x[2]));
      if (!(d <= distance + 1e-6 * (size + distance)))
        Violation("a node tied to a point beyond ContactDistance");
      if (!(d <= ScanDistance(undeformed, x) + 1e-6 * (size + distance)))
        Violation("a node tied to a point farther than the closest point of the bone");
    }
    ++t;
  }
  if (t != tied)
    Violation("a tied node that is not a boundary node, or out of order");
}

// Flips one edge or drops one cell: same points, other connectivity.
vtkSmartPointer<vtkPolyData> Reconnected(vtkPolyData* bone, FuzzBytes& in) {
  auto other = vtkSmartPointer<vtkPolyData>::New();
  other->DeepCopy(bone);
  vtkCellArray* polys = other->GetPolys();
  if (polys->GetNumberOfCells() == 0)
    return other;
  vtkNew<vtkCellArray> changed;
  const vtkIdType chosen = in.range(0, int(polys->GetNumberOfCells()) - 1);
  const bool drop = in.flag();
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < polys->GetNumberOfCells(); ++c) {
    polys->GetCellAtId(c, ids);
    if (c == chosen) {
      if (drop && polys->GetNumberOfCells() > 1)
        continue;
      ids->SetId(0, in.range(0, int(other->GetNumberOfPoints()) - 1));
    }
    changed->InsertNextCell(ids);
  }
  other->SetPolys(changed);
  return other;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzBytes in(data, size);
  // Scale and offset: ordinary, far from the origin (2^20), large but accepted (2^90), and refused
  // (2^500; 2^1016, where points minus Displacement overflow).
  static const double scales[8] = {
      1.0, 1.0, std::ldexp(1.0, 500), std::ldexp(1.0, 1016), std::ldexp(1.0, 90), 1.0, 1.0, 1.0};
  const int mode = in.byte() % 8;
  const double scale = scales[mode], offset = mode == 1 || mode == 5 ? std::ldexp(1.0, 20) : 0.0;
  Bone bone = MakeBone(in, scale, offset);
  if (!ValidateBone(bone.data))
    return 0;

  vtkNew<vtkUnstructuredGrid> tissue;
  vtkNew<vtkPoints> tissuePoints;
  tissuePoints->SetDataTypeToDouble();
  const int tissueCount = in.range(1, 12);
  for (int i = 0; i < tissueCount; ++i)
    tissuePoints->InsertNextPoint(offset + Grid(in, scale), offset + Grid(in, scale),
                                  offset + Grid(in, scale));
  tissue->SetPoints(tissuePoints);
  std::vector<vtkIdType> boundary;
  for (int i = 0; i < tissueCount; ++i)
    if (in.byte() % 4 != 0)
      boundary.push_back(i);
  const double distance = scale * double(in.range(1, 64)) / 16.0;
  const double release = in.flag() ? scale * double(in.range(0, 32)) / 16.0 : 0.0;
  double bounds[6];
  bone.data->GetBounds(bounds);
  const double extent = std::max({bounds[1] - bounds[0], bounds[3] - bounds[2],
                                  bounds[5] - bounds[4], std::abs(bounds[0]), std::abs(bounds[1])});

  // As the filter does: the bone taken by BoneInput, the contact built when it says so.
  BoneInput input;
  if (!input.update(bone.data, 1, distance, release))
    Violation("BoneInput refused a bone that ValidateBone accepted");
  if (!input.contactChanged())
    Violation("BoneInput reports a contact for a bone it never saw");
  ContactCache cache;
  const Status built =
      cache.build(tissue, boundary, bone.data, input.undeformed(), distance, release);
  if (!built) {
    if (built.message.empty())
      Violation("a contact error without a message");
    return 0;
  }
  input.contactBuilt();
  const ContactMap first = cache.map();
  CheckMap(first, tissue, boundary, bone, distance, extent);

  // Derived sets and displacements, as the filter builds them.
  const ContactModelChoice model = static_cast<ContactModelChoice>(in.range(0, 2));
  std::vector<int> segmentOfBonePoint;
  if (in.flag())
    segmentOfBonePoint.assign(std::size_t(bone.data->GetNumberOfPoints()), 0);
  const NodeSets sets = MakeNodeSets(
      first, boundary, model, bone.data->GetPointData()->GetArray("Sliding"), segmentOfBonePoint);
  vtkDataArray* displacement = bone.data->GetPointData()->GetArray("Displacement");
  const RowVectors3d moves = MovableDisplacements(first, displacement);
  if (moves.rows() != Eigen::Index(sets.movable.size()) || !moves.allFinite())
    Violation("movable displacements inconsistent with the node sets or not finite");
  if (sets.slidingNormal.size() != sets.sliding.size() || sets.kept.size() != boundary.size())
    Violation("node sets of inconsistent sizes");
  if (ReleasedCount(first) + sets.constrained.size() != first.tiedNodes.size())
    Violation("released and constrained nodes do not add up to the tied nodes");

  // A cut edit: points and Displacement move together, the undeformed bone stays. The cache must
  // give what a fresh one gives. One input in four (it triples an execution's cost).
  if (in.byte() % 4 != 0)
    return 0;
  auto edited = vtkSmartPointer<vtkPolyData>::New();
  edited->DeepCopy(bone.data);
  vtkDataArray* d = edited->GetPointData()->GetArray("Displacement");
  for (vtkIdType i = 0; i < edited->GetNumberOfPoints(); ++i) {
    double p[3], u[3];
    edited->GetPoint(i, p);
    d->GetTuple(i, u);
    for (int c = 0; c < 3; ++c) {
      const double step = in.flag() ? Grid(in, scale) / 8.0 : 0.0;
      p[c] += step;
      u[c] += step;
    }
    edited->GetPoints()->SetPoint(i, p);
    d->SetTuple(i, u);
  }
  // The rest of this check needs an exact edit (no overflow, no rounding).
  if (!ValidateBone(edited))
    return 0;
  Bone next{Reconnected(edited, in), bone.planarCellsOnly};
  if (!ValidateBone(next.data))
    return 0;
  for (vtkPolyData* step : {edited.GetPointer(), next.data.GetPointer()}) {
    if (!input.update(step, 1, distance, release))
      return 0;
    if (step == edited.GetPointer() && input.contactChanged())
      Violation("a cut edit (points and Displacement moved together) rebuilds the contact");
    if (input.contactChanged()) {
      if (!cache.build(tissue, boundary, step, input.undeformed(), distance, release))
        return 0;
      input.contactBuilt();
    }
    std::vector<double> undeformed;
    UndeformedPoints(step, step->GetPointData()->GetArray("Displacement"), undeformed);
    ContactCache fresh;
    if (!fresh.build(tissue, boundary, step, undeformed, distance, release))
      Violation("a fresh cache refused what the updated cache accepted");
    if (!SameMap(cache.map(), fresh.map()))
      Violation("the cached contact map differs from a fresh one");
  }
  return 0;
}
