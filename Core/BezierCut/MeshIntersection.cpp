// SPDX-License-Identifier: BSD-3-Clause
#include "BezierCut/MeshIntersection.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace faceplan {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

double Cross2(const Vector2d& a, const Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// A triangle's corners, unit normal (zero when degenerate) and longest edge, computed once per
// pair instead of once per segment test.
struct TriangleFrame {
  Vector3d a, b, c, n;
  double longestEdge;
  TriangleFrame(const Tri& t, const RowVectors3d& P)
      : a(P.row(t.v[0]).transpose()), b(P.row(t.v[1]).transpose()), c(P.row(t.v[2]).transpose()) {
    n = (b - a).cross(c - a);
    const double nn = n.norm();
    n = nn > 0 ? Vector3d(n / nn) : Vector3d::Zero();
    longestEdge = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  }
  bool degenerate() const { return n.isZero(0.0); }
};

// Does segment pq meet the interior of triangle T (touching an edge or vertex of the triangle, or
// the segment only touching it with an endpoint on its border, does not count)?
bool SegmentHitsTriangle(const Vector3d& p, const Vector3d& q, const TriangleFrame& T) {
  if (T.degenerate())
    return false; // degenerate triangles are reported by the flip check
  const Vector3d &a = T.a, &b = T.b, &c = T.c, &n = T.n;
  const double scale = std::max(T.longestEdge, (q - p).norm());
  const double eps = 1e-9 * scale;
  const double dp = (p - a).dot(n), dq = (q - a).dot(n);
  if ((dp > eps && dq > eps) || (dp < -eps && dq < -eps))
    return false;
  if (std::abs(dp) <= eps && std::abs(dq) <= eps) {
    // Coplanar: work in the plane of the two largest normal components.
    int ax = 0;
    n.cwiseAbs().maxCoeff(&ax);
    const int i = (ax + 1) % 3, j = (ax + 2) % 3;
    auto P2 = [&](const Vector3d& x) { return Vector2d(x[i], x[j]); };
    Vector2d P = P2(p), Q = P2(q), A = P2(a), B = P2(b), C = P2(c);
    if (Cross2(B - A, C - A) < 0)
      std::swap(B, C);
    const double area2 = Cross2(B - A, C - A);
    const double tolA = 1e-9 * area2;
    auto inside = [&](const Vector2d& X) {
      return Cross2(B - A, X - A) > tolA && Cross2(C - B, X - B) > tolA &&
             Cross2(A - C, X - C) > tolA;
    };
    if (inside(P) || inside(Q))
      return true;
    const double tolL = 1e-9 * scale * scale;
    auto proper = [&](const Vector2d& E0, const Vector2d& E1) {
      const double o1 = Cross2(Q - P, E0 - P), o2 = Cross2(Q - P, E1 - P);
      const double o3 = Cross2(E1 - E0, P - E0), o4 = Cross2(E1 - E0, Q - E0);
      return ((o1 > tolL && o2 < -tolL) || (o1 < -tolL && o2 > tolL)) &&
             ((o3 > tolL && o4 < -tolL) || (o3 < -tolL && o4 > tolL));
    };
    return proper(A, B) || proper(B, C) || proper(C, A);
  }
  const double s = std::clamp(dp / (dp - dq), 0.0, 1.0);
  const Vector3d x = p + s * (q - p);
  // Barycentric coordinates of x in abc.
  const Vector3d v0 = b - a, v1 = c - a, v2 = x - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0),
               d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 0))
    return false;
  const double bv = (d11 * d20 - d01 * d21) / den, bw = (d00 * d21 - d01 * d20) / den;
  const double bu = 1.0 - bv - bw;
  const double tol = 1e-9;
  return bu > tol && bv > tol && bw > tol;
}

} // namespace

// True when every corner of `other` lies on the same side of T's plane, farther than 1e-6 of the
// pair's longest edge: then no segment test below can report a crossing, since each of them accepts
// only points within 1e-9 of that length (times sqrt(3) in the coplanar branch) of both planes.
bool SeparatedByPlane(const TriangleFrame& T, const TriangleFrame& other, double margin) {
  if (T.degenerate())
    return false;
  const double d[3] = {(other.a - T.a).dot(T.n), (other.b - T.a).dot(T.n),
                       (other.c - T.a).dot(T.n)};
  return (d[0] > margin && d[1] > margin && d[2] > margin) ||
         (d[0] < -margin && d[1] < -margin && d[2] < -margin);
}

bool TrianglesIntersect(const Tri& A, const Tri& B, const RowVectors3d& P, bool skipSharedVertex) {
  int shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (A.v[i] == B.v[j])
        ++shared;
  if (shared >= 2 || (shared == 1 && skipSharedVertex))
    return false;
  const TriangleFrame a(A, P), b(B, P);
  const double margin = 1e-6 * std::max(a.longestEdge, b.longestEdge);
  if (SeparatedByPlane(a, b, margin) || SeparatedByPlane(b, a, margin))
    return false;
  const Vector3d* ac[3] = {&a.a, &a.b, &a.c};
  const Vector3d* bc[3] = {&b.a, &b.b, &b.c};
  for (int e = 0; e < 3; ++e) {
    if (SegmentHitsTriangle(*ac[e], *ac[(e + 1) % 3], b))
      return true;
    if (SegmentHitsTriangle(*bc[e], *bc[(e + 1) % 3], a))
      return true;
  }
  return false;
}

bool TriangleBoxesApart(const Tri& A, const Tri& B, const RowVectors3d& P) {
  auto box = [&](const Tri& t, Eigen::Array3d& mn, Eigen::Array3d& mx) {
    mn = P.row(t.v[0]).transpose().array();
    mx = mn;
    for (int k = 1; k < 3; ++k) {
      mn = mn.min(P.row(t.v[k]).transpose().array());
      mx = mx.max(P.row(t.v[k]).transpose().array());
    }
  };
  Eigen::Array3d amn, amx, bmn, bmx;
  box(A, amn, amx);
  box(B, bmn, bmx);
  const double margin = 1e-6 * std::max((amx - amn).maxCoeff(), (bmx - bmn).maxCoeff());
  return (amn > bmx + margin).any() || (bmn > amx + margin).any();
}

TriangleBoxTree::TriangleBoxTree(const std::vector<Tri>& tris, const RowVectors3d& P,
                                 const std::vector<std::int64_t>& ids)
    : tris_(tris), points_(P), ids_(ids) {
  // KdBVH indexes its objects with int: the objects are positions in ids_.
  std::vector<int> objects;
  if (ids_.size() < std::size_t(std::numeric_limits<int>::max())) {
    objects.reserve(ids_.size());
    boxes_.reserve(ids_.size());
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      objects.push_back(int(k));
      boxes_.push_back(grownBox(ids_[k]));
    }
  }
  tree_.init(objects.begin(), objects.end(), boxes_.begin(), boxes_.end());
}

TriangleBoxTree::Box TriangleBoxTree::grownBox(std::int64_t t) const {
  Box box(points_.row(tris_[t].v[0]).transpose());
  for (int k = 1; k < 3; ++k)
    box.extend(points_.row(tris_[t].v[k]).transpose());
  const double margin = 1e-6 * box.sizes().maxCoeff();
  box.min().array() -= margin;
  box.max().array() += margin;
  return box;
}

void TriangleBoxTree::candidates(std::int64_t t, std::vector<std::int64_t>& out) const {
  struct Collect {
    const Box query;
    const TriangleBoxTree& self;
    std::vector<std::int64_t>& found;
    bool intersectVolume(const Box& volume) const { return volume.intersects(query); }
    bool intersectObject(int k) {
      // A leaf's volume holds up to two objects: test each object's own box.
      if (self.boxes_[std::size_t(k)].intersects(query))
        found.push_back(self.ids_[std::size_t(k)]);
      return false; // keep searching
    }
  };
  out.clear();
  Collect collect{grownBox(t), *this, out};
  Eigen::BVIntersect(tree_, collect);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::vector<Tri> FanTriangles(const SurfaceMesh& mesh) {
  std::vector<Tri> tris;
  for (std::int64_t c = 0; c < mesh.numCells(); ++c) {
    const std::int64_t m = mesh.cellSize(c);
    const std::int64_t* ids = mesh.cell(c);
    for (std::int64_t k = 1; k + 1 < m; ++k)
      tris.push_back(Tri{{ids[0], ids[k], ids[k + 1]}});
  }
  return tris;
}

std::vector<std::int64_t> NewIntersections(const std::vector<Tri>& tris, const RowVectors3d& before,
                                           const RowVectors3d& after,
                                           const std::vector<std::uint8_t>& activeTri) {
  std::vector<std::int64_t> active;
  Eigen::Array3d lo = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    if (!activeTri[t])
      continue;
    active.push_back(std::int64_t(t));
    for (int k = 0; k < 3; ++k) {
      lo = lo.min(after.row(tris[t].v[k]).transpose().array());
      hi = hi.max(after.row(tris[t].v[k]).transpose().array());
    }
  }
  std::vector<std::int64_t> result;
  if (active.empty())
    return result;
  // Every triangle that TriangleBoxesApart may not rule out against some active triangle: its box
  // grown by 1e-6 of its extent meets the active region's box grown by 1e-6 of the region's.
  const Eigen::Array3d grownLo = lo - 1e-6 * (hi - lo).maxCoeff();
  const Eigen::Array3d grownHi = hi + 1e-6 * (hi - lo).maxCoeff();
  std::vector<std::int64_t> nearby;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    Eigen::Array3d mn = after.row(tris[t].v[0]).transpose().array(), mx = mn;
    for (int k = 1; k < 3; ++k) {
      mn = mn.min(after.row(tris[t].v[k]).transpose().array());
      mx = mx.max(after.row(tris[t].v[k]).transpose().array());
    }
    const double margin = 1e-6 * (mx - mn).maxCoeff();
    if (!((mx + margin < grownLo).any() || (mn - margin > grownHi).any()))
      nearby.push_back(std::int64_t(t));
  }
  TriangleBoxTree tree(tris, after, nearby);
  std::vector<std::uint8_t> flagged(tris.size(), 0);
  std::vector<std::int64_t> cand;
  for (std::int64_t a : active) {
    tree.candidates(a, cand);
    for (std::int64_t b : cand) {
      if (b == a || (activeTri[b] && b < a))
        continue; // each pair once
      if (!TrianglesIntersect(tris[a], tris[b], after, false))
        continue;
      if (TrianglesIntersect(tris[a], tris[b], before, false))
        continue; // was already so
      flagged[a] = flagged[b] = 1;
    }
  }
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (flagged[t])
      result.push_back(std::int64_t(t));
  return result;
}

std::int64_t CountNewIntersections(const SurfaceMesh& cells, const RowVectors3d& before,
                                   const RowVectors3d& after,
                                   const std::vector<std::uint8_t>& active,
                                   std::int64_t* firstTriangle) {
  std::vector<Tri> tris = FanTriangles(cells);
  std::vector<std::uint8_t> activeTri(tris.size(), 0);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (std::size_t(tris[t].v[k]) < active.size() && active[tris[t].v[k]])
        activeTri[t] = 1;
  std::vector<std::int64_t> bad = NewIntersections(tris, before, after, activeTri);
  if (firstTriangle)
    *firstTriangle = bad.empty() ? -1 : bad.front();
  return std::int64_t(bad.size());
}

} // namespace faceplan
