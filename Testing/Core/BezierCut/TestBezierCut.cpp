// SPDX-License-Identifier: BSD-3-Clause
// BezierCut contract tests: moved vertices on S, the others untouched bit for bit, topology
// unchanged, no flipped / degenerate / newly intersecting triangles, clear errors for bad curves.
#include "BezierCut/BezierCut.h"
#include "BezierCut/CutMapping.h"
#include "BezierCut/DefaultCurves.h"
#include "BezierCut/MeshIntersection.h"
#include "ROIExtract/ROIExtract.h"
#include "Support/FaceplanTestMeshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <random>

using namespace faceplan;
using Eigen::Vector3d;
using Curve = std::vector<Vector3d>;

namespace {

// Independent evaluation (de Casteljau) of a composite cubic curve at global parameter u.
Vector3d DeCasteljau(const Curve& P, double u) {
  const int k = int(P.size() - 1) / 3;
  int s = std::min(int(u * k), k - 1);
  double t = u * k - s;
  Vector3d q[4] = {P[3 * s], P[3 * s + 1], P[3 * s + 2], P[3 * s + 3]};
  for (int r = 3; r > 0; --r)
    for (int i = 0; i < r; ++i)
      q[i] = (1 - t) * q[i] + t * q[i + 1];
  return q[0];
}
Vector3d RefSurface(const Curve& U, const Curve& V, double u, double v) {
  return DeCasteljau(U, u) + DeCasteljau(V, v) - U[0];
}

Curve Line(const Vector3d& a, const Vector3d& b, int segments = 1) {
  Curve c;
  for (int i = 0; i <= 3 * segments; ++i)
    c.push_back(a + (b - a) * (double(i) / (3 * segments)));
  return c;
}

Vector3d Row(const RowVectors3d& P, Eigen::Index i) {
  return P.row(i).transpose();
}
Vector3d AreaVec(const RowVectors3d& P, const std::int64_t* t) {
  return 0.5 * (Row(P, t[1]) - Row(P, t[0])).cross(Row(P, t[2]) - Row(P, t[0]));
}

// Moller-Trumbore: does the open segment pq cross the interior of triangle abc?
bool SegTri(const Vector3d& p, const Vector3d& q, const Vector3d& a, const Vector3d& b,
            const Vector3d& c) {
  const Vector3d d = q - p, e1 = b - a, e2 = c - a, h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-14 * e1.norm() * e2.norm() * d.norm())
    return false;
  const Vector3d s = p - a;
  const double f = 1.0 / det, u = f * s.dot(h);
  if (u <= 1e-9 || u >= 1 - 1e-9)
    return false;
  const Vector3d qq = s.cross(e1);
  const double v = f * d.dot(qq);
  if (v <= 1e-9 || u + v >= 1 - 1e-9)
    return false;
  const double t = f * e2.dot(qq);
  return t > 1e-9 && t < 1 - 1e-9;
}

struct ContractReport {
  std::int64_t flipped = 0, degenerate = 0, intersecting = 0, unmovedChanged = 0;
  double maxOffSurface = 0;
};

// `expectedNormal` (if nonzero): triangles whose vertices all moved must face it.
ContractReport CheckContract(const SurfaceMesh& m, const BezierCutResult& r, const Curve& U,
                             const Curve& V, const Vector3d& expectedNormal) {
  ContractReport c;
  const Eigen::Index n = m.numPoints();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!r.moved[i]) {
      if (std::memcmp(&m.points(i, 0), &r.points(i, 0), 3 * sizeof(double)) != 0 ||
          r.displacement.row(i).squaredNorm() != 0.0)
        ++c.unmovedChanged;
    } else {
      const auto& uv = r.parameters[i];
      EXPECT_TRUE(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1);
      c.maxOffSurface =
          std::max(c.maxOffSurface, (Row(r.points, i) - RefSurface(U, V, uv.x(), uv.y())).norm());
      EXPECT_LT((Row(r.points, i) - Row(m.points, i) - Row(r.displacement, i)).norm(), 1e-12);
    }
  }
  std::vector<const std::int64_t*> tris, touched;
  for (std::int64_t t = 0; t < m.numCells(); ++t) {
    const std::int64_t* ids = m.cell(t);
    tris.push_back(ids);
    const int mv = r.moved[ids[0]] + r.moved[ids[1]] + r.moved[ids[2]];
    if (mv == 0)
      continue;
    touched.push_back(ids);
    const Vector3d a0 = AreaVec(m.points, ids), a1 = AreaVec(r.points, ids);
    if (a1.norm() <= 1e-8 * a0.norm()) {
      ++c.degenerate;
      continue;
    }
    if (mv == 3 && expectedNormal.squaredNorm() > 0) {
      if (a1.dot(expectedNormal) <= 0)
        ++c.flipped;
      if (a0.dot(expectedNormal) > 0 && a1.dot(a0) <= 0)
        ++c.flipped;
    } else if (a1.dot(a0) <= 0) {
      ++c.flipped;
    }
  }
  // Brute force: triangles touching moved vertices against all triangles sharing no vertex.
  for (const std::int64_t* a : touched)
    for (const std::int64_t* b : tris) {
      if (a == b)
        continue;
      bool share = false;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          share |= a[i] == b[j];
      if (share)
        continue;
      bool hit = false;
      for (int e = 0; e < 3 && !hit; ++e) {
        hit |= SegTri(Row(r.points, a[e]), Row(r.points, a[(e + 1) % 3]), Row(r.points, b[0]),
                      Row(r.points, b[1]), Row(r.points, b[2]));
        hit |= SegTri(Row(r.points, b[e]), Row(r.points, b[(e + 1) % 3]), Row(r.points, a[0]),
                      Row(r.points, a[1]), Row(r.points, a[2]));
      }
      c.intersecting += hit;
    }
  return c;
}

// The whole contract at once, with every count in the message when it fails: nothing unmoved
// changed, no flipped, degenerate or intersecting triangle, moved vertices within
// `maxOffSurface` of the surface.
::testing::AssertionResult ContractHeld(const ContractReport& c, double maxOffSurface) {
  if (c.unmovedChanged == 0 && c.flipped == 0 && c.degenerate == 0 && c.intersecting == 0 &&
      c.maxOffSurface < maxOffSurface)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "unmoved vertices changed " << c.unmovedChanged << ", flipped " << c.flipped
         << ", degenerate " << c.degenerate << ", intersecting " << c.intersecting
         << ", largest distance off the surface " << c.maxOffSurface << " (limit " << maxOffSurface
         << ")";
}

ROIResult RoiWhere(const SurfaceMesh& m, const std::function<bool(const Vector3d&)>& pred) {
  std::vector<std::uint8_t> sel(m.numPoints());
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    sel[i] = pred(Row(m.points, i));
  ROIResult r;
  EXPECT_TRUE(ComputeROI(m, sel, r).ok);
  return r;
}

} // namespace

// ---------------------------------------------------------------- the surface itself

TEST(BezierSurface, EvaluationMatchesDeCasteljauAndDerivatives) {
  Curve U = {{0, 0, 0},    {1, 0, 0.5},    {2, 0, 0.5}, {3, 0, 0},
             {4, 0, -0.5}, {5, 0.2, -0.5}, {6, 0.3, 0}};
  Curve V = {{0, 0, 0}, {0, 1, 0.2}, {0.1, 2, 0.2}, {0, 3, 0}};
  BezierSurface S;
  Status s = BezierSurface::Create(U, V, false, S);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(S.segmentsU(), 2);
  EXPECT_EQ(S.segmentsV(), 1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0.01, 0.99);
  for (int k = 0; k < 50; ++k) {
    const double u = uni(rng), v = uni(rng);
    EXPECT_LT((S.evaluate(u, v) - RefSurface(U, V, u, v)).norm(), 1e-12);
    Vector3d P, Su, Sv, Suu, Svv;
    S.derivatives(u, v, P, Su, Sv, Suu, Svv);
    const double h = 1e-6;
    if (std::abs(u - 0.5) > 2 * h) { // not across the joint
      EXPECT_LT((Su - (RefSurface(U, V, u + h, v) - RefSurface(U, V, u - h, v)) / (2 * h)).norm(),
                1e-5);
    }
    EXPECT_LT((Sv - (RefSurface(U, V, u, v + h) - RefSurface(U, V, u, v - h)) / (2 * h)).norm(),
              1e-5);
    EXPECT_NEAR(S.unitNormal(u, v).dot(Su.cross(Sv).normalized()), 1.0, 1e-12);
  }
  EXPECT_LT((S.evaluate(0, 0) - U[0]).norm(), 1e-15);
  EXPECT_LT((S.evaluate(1, 0) - U.back()).norm(), 1e-12);
  EXPECT_LT((S.evaluate(0, 1) - V.back()).norm(), 1e-12);
  BezierSurface F;
  ASSERT_TRUE(BezierSurface::Create(U, V, true, F).ok);
  EXPECT_NEAR(F.unitNormal(0.3, 0.3).dot(S.unitNormal(0.3, 0.3)), -1.0, 1e-12);
}

TEST(BezierSurface, ProjectionIsClosestPoint) {
  Curve U = {{-1, -1, 0}, {-0.3, -1, 0.6}, {0.3, -1, 0.6}, {1, -1, 0}};
  Curve V = {{-1, -1, 0}, {-1, -0.3, 0.3}, {-1, 0.3, -0.3}, {-1, 1, 0}};
  BezierSurface S;
  ASSERT_TRUE(BezierSurface::Create(U, V, false, S).ok);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-0.8, 0.8), z(-0.5, 0.9);
  for (int k = 0; k < 40; ++k) {
    const Vector3d x(xy(rng), xy(rng), z(rng));
    const SurfaceProjection p = S.project(x);
    double best = 1e300;
    for (int i = 0; i <= 300; ++i)
      for (int j = 0; j <= 300; ++j)
        best = std::min(best, (RefSurface(U, V, i / 300.0, j / 300.0) - x).norm());
    const double d = (p.point - x).norm();
    EXPECT_LE(d, best + 1e-9) << "not the closest point for " << x.transpose();
    if (p.inside) {
      EXPECT_NEAR(std::abs(p.signedDistance), d, 1e-9); // orthogonal foot point
    }
  }
  // A point beyond the u = 1 border projects outside the patch.
  EXPECT_FALSE(S.project(Vector3d(3, 0, 0)).inside);
  EXPECT_TRUE(S.project(Vector3d(0, 0, 2)).inside);
  EXPECT_GT(S.project(Vector3d(0, 0, 2)).signedDistance, 0); // n = Su x Sv points to +z here
}

TEST(BezierSurface, TessellationFollowsNormal) {
  Curve U = Line({0, 0, 0}, {2, 0, 0}, 2), V = Line({0, 0, 0}, {0, 1, 0});
  for (bool flip : {false, true}) {
    BezierSurface S;
    ASSERT_TRUE(BezierSurface::Create(U, V, flip, S).ok);
    SurfaceMesh t;
    S.tessellate(5, t);
    EXPECT_EQ(t.numPoints(), (2 * 5 + 1) * (5 + 1));
    EXPECT_EQ(t.numCells(), 2 * 2 * 5 * 5);
    for (std::int64_t c = 0; c < t.numCells(); ++c)
      EXPECT_GT(AreaVec(t.points, t.cell(c)).z() * (flip ? -1 : 1), 0);
  }
}

// ---------------------------------------------------------------- errors

TEST(BezierSurface, IllDefinedControlPointsAreNamed) {
  BezierSurface S;
  const Curve U = Line({0, 0, 0}, {1, 0, 0}), V = Line({0, 0, 0}, {0, 1, 0});
  struct Case {
    Curve u, v;
    const char* expect;
  };
  Curve wrongCount = U;
  wrongCount.push_back({2, 0, 0});
  Curve notShared = V;
  notShared[0] = {0, 0, 0.1};
  Curve coincident = U;
  coincident[2] = coincident[1];
  Curve parallel = Line({0, 0, 0}, {0.5, 0, 0});
  Curve loop = {{0, 0, 0}, {2, 1.5, 0}, {-1, 1.5, 0}, {1, 0, 0}}; // a loop: crosses itself
  Curve fold = {{0, 0, 0}, {2, 0, 0}, {2, 0.3, 0}, {0, -0.1, 0}}; // turns back across itself
  Curve cusp = {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}};      // tangent vanishes
  Curve allSame(4, Vector3d(1, 1, 1));
  Curve nan = U;
  nan[3].x() = std::nan("");
  std::vector<Case> cases = {
      {wrongCount, V, "3k+1"},
      {U, notShared, "first control points not shared"},
      {coincident, V, "degenerate"},
      {U, parallel, "degenerate"},
      {loop, Line({0, 0, 0}, {0, 0, 1}), "self-intersecting"},
      {fold, Line({0, 0, 0}, {0, 0, 1}), "self-intersecting"},
      {cusp, Line({0, 0, 0}, {0, 0, 1}), "degenerate"},
      {allSame, allSame, "degenerate"},
      {nan, V, "not finite"},
  };
  for (const Case& c : cases) {
    Status s = BezierSurface::Create(c.u, c.v, false, S);
    EXPECT_FALSE(s.ok) << c.expect;
    EXPECT_NE(s.message.find(c.expect), std::string::npos)
        << "expected '" << c.expect << "' in: " << s.message;
  }
  EXPECT_TRUE(BezierSurface::Create(U, V, false, S).ok);
}

TEST(BezierCut, ErrorsGiveEmptyResult) {
  SurfaceMesh m = testmesh::Icosphere(2);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.3; });
  BezierCutResult r;
  // Far away patch: no ROI vertex projects inside it.
  Curve U = Line({10, 10, 0.7}, {11, 10, 0.7}), V = Line({10, 10, 0.7}, {10, 11, 0.7});
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, {}, r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("not meeting the ROI"), std::string::npos) << s.message;
  EXPECT_EQ(r.points.rows(), 0);
  // Bad curve is reported through the cut as well.
  Curve V2 = Line({0, 0, 1}, {0, 1, 1});
  s = BezierCut(m, roi.mask, roi.boundary, Line({0, 0, 0}, {1, 0, 0}), V2, {}, r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("first control points not shared"), std::string::npos) << s.message;
  // Wrong array sizes, empty ROI.
  s = BezierCut(m, {1, 1}, roi.boundary, U, V, {}, r);
  EXPECT_FALSE(s.ok);
  s = BezierCut(m, std::vector<std::uint8_t>(m.numPoints(), 0), roi.boundary, U, V, {}, r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("ROI is empty"), std::string::npos) << s.message;
}

// ---------------------------------------------------------------- cut and fill

TEST(BezierCut, PlaneCutOfSphereCap) {
  SurfaceMesh m = testmesh::Icosphere(4);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.3; });
  const double h = 0.7;
  Curve U = Line({-1.5, -1.5, h}, {1.5, -1.5, h}), V = Line({-1.5, -1.5, h}, {-1.5, 1.5, h});
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, {}, r);
  ASSERT_TRUE(s.ok) << s.message;
  // Exactly the ROI interior vertices above the plane move.
  std::int64_t expected = 0;
  for (Eigen::Index i = 0; i < m.numPoints(); ++i) {
    const bool shouldMove = roi.mask[i] && !roi.boundary[i] && m.points(i, 2) > h;
    EXPECT_EQ(bool(r.moved[i]), shouldMove) << "vertex " << i;
    expected += shouldMove;
    if (r.moved[i]) {
      EXPECT_NEAR(r.points(i, 2), h, 1e-12);
    }
  }
  EXPECT_GT(expected, 100);
  EXPECT_EQ(r.numMoved, expected);
  EXPECT_TRUE(ContractHeld(CheckContract(m, r, U, V, Vector3d(0, 0, 1)), 1e-12));
  EXPECT_LE(r.maxDistanceToSurface, 1e-12);
  EXPECT_EQ(r.operativeSurface.numPoints(), 17 * 17);
  // No new intersections by Core's own check either.
  EXPECT_EQ(CountNewIntersections(m, m.points, r.points, r.moved), 0);
}

TEST(BezierCut, OntoAMadeSurfaceEqualsFromCurves) {
  SurfaceMesh m = testmesh::Icosphere(3);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.3; });
  Curve U = Line({-1.5, -1.5, 0.7}, {1.5, -1.5, 0.7}),
        V = Line({-1.5, -1.5, 0.7}, {-1.5, 1.5, 0.8});
  CutMeshTopology topology;
  ASSERT_TRUE(PrepareCutMesh(m, topology).ok);
  for (const bool flip : {false, true}) {
    BezierCutOptions options;
    options.flipNormal = flip;
    BezierCutResult fromCurves, ontoSurface;
    ASSERT_TRUE(BezierCut(m, topology, roi.mask, roi.boundary, U, V, options, fromCurves).ok);
    BezierSurface surface;
    ASSERT_TRUE(BezierSurface::Create(U, V, flip, surface).ok);
    options.flipNormal = !flip; // not read: the surface's own orientation counts
    ASSERT_TRUE(BezierCut(m, topology, roi.mask, roi.boundary, surface, options, ontoSurface).ok);
    EXPECT_GT(fromCurves.numMoved, 0);
    EXPECT_EQ(ontoSurface.moved, fromCurves.moved);
    EXPECT_TRUE(ontoSurface.points == fromCurves.points); // bit for bit
  }
  BezierCutResult r;
  const Status none = BezierCut(m, topology, roi.mask, roi.boundary, BezierSurface{}, {}, r);
  EXPECT_FALSE(none.ok);
  EXPECT_NE(none.message.find("no surface"), std::string::npos) << none.message;
  EXPECT_EQ(r.points.rows(), 0);
}

TEST(BezierCut, FlipNormalCutsTheOtherSide) {
  SurfaceMesh m = testmesh::Icosphere(3);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.3; });
  Curve U = Line({-1.5, -1.5, 0.7}, {1.5, -1.5, 0.7}),
        V = Line({-1.5, -1.5, 0.7}, {-1.5, 1.5, 0.7});
  BezierCutOptions o;
  o.flipNormal = true; // normal -z: the ROI band between the boundary and z = 0.7 is cut
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, o, r);
  ASSERT_TRUE(s.ok) << s.message;
  // The unflipped cut of the same ROI moves the cap above the plane instead.
  BezierCutResult up;
  o.flipNormal = false;
  ASSERT_TRUE(BezierCut(m, roi.mask, roi.boundary, U, V, o, up).ok);
  ASSERT_GT(r.numMoved, 0);
  ASSERT_GT(up.numMoved, 0);
  for (Eigen::Index i = 0; i < m.numPoints(); ++i) {
    if (r.moved[i]) {
      EXPECT_LT(m.points(i, 2), 0.7) << "vertex " << i << " above the plane moved";
      EXPECT_NEAR(r.points(i, 2), 0.7, 1e-12) << "vertex " << i << " not on the plane";
    } else {
      EXPECT_EQ(r.displacement.row(i).norm(), 0.0) << "unmoved vertex " << i << " changed";
    }
    EXPECT_FALSE(r.moved[i] && up.moved[i]) << "vertex " << i << " moved by both sides";
  }
  ContractReport c = CheckContract(m, r, U, V, Vector3d::Zero());
  EXPECT_EQ(c.flipped + c.degenerate + c.intersecting + c.unmovedChanged, 0);
}

TEST(BezierCut, FillRaisesSphereCap) {
  SurfaceMesh m = testmesh::Icosphere(4);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.6; });
  const double h = 0.95;
  Curve U = Line({-1.5, -1.5, h}, {1.5, -1.5, h}), V = Line({-1.5, -1.5, h}, {-1.5, 1.5, h});
  BezierCutOptions o;
  o.operation = CutOperation::Fill;
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, o, r);
  ASSERT_TRUE(s.ok) << s.message;
  std::int64_t expected = 0;
  for (Eigen::Index i = 0; i < m.numPoints(); ++i) {
    const bool shouldMove = roi.mask[i] && !roi.boundary[i] && m.points(i, 2) < h;
    EXPECT_EQ(bool(r.moved[i]), shouldMove) << "vertex " << i;
    expected += shouldMove;
  }
  EXPECT_GT(expected, 20);
  EXPECT_TRUE(ContractHeld(CheckContract(m, r, U, V, Vector3d(0, 0, 1)), 1e-12));
}

TEST(BezierCut, CurvedCompositeSurface) {
  SurfaceMesh m = testmesh::Icosphere(4);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.2; });
  // An arch in x (one segment) swept along a gently bent two-segment line in y.
  Curve U = {{-1.5, -1.5, 0.4}, {-0.5, -1.5, 0.9}, {0.5, -1.5, 0.9}, {1.5, -1.5, 0.4}};
  Curve V = {{-1.5, -1.5, 0.4}, {-1.5, -1, 0.4}, {-1.5, -0.5, 0.45}, {-1.5, 0, 0.45},
             {-1.5, 0.5, 0.45}, {-1.5, 1, 0.4},  {-1.5, 1.5, 0.4}};
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, {}, r);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_GT(r.numMoved, 50);
  EXPECT_TRUE(ContractHeld(CheckContract(m, r, U, V, Vector3d::Zero()), 1e-10));
  // Moved vertices were on the normal side: the surface is below them.
  BezierSurface S;
  ASSERT_TRUE(BezierSurface::Create(U, V, false, S).ok);
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    if (r.moved[i]) {
      EXPECT_GT(S.project(Row(m.points, i)).signedDistance, 0);
    }
}

TEST(BezierCut, SlabNeedsTangentialRelaxation) {
  // A thin plate cut across: direct projection collapses its side walls onto lines.
  SurfaceMesh m = testmesh::Box({-0.15, -0.6, -1}, {0.15, 0.6, 1}, 0.05);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.01; });
  const double h = 0.52;
  Curve U = Line({-1, -1, h}, {1, -1, h}), V = Line({-1, -1, h}, {-1, 1, h});
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, {}, r);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_GT(r.intermediarySteps, 0);
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    EXPECT_EQ(bool(r.moved[i]), roi.mask[i] && !roi.boundary[i] && m.points(i, 2) > h);
  EXPECT_TRUE(ContractHeld(CheckContract(m, r, U, V, Vector3d(0, 0, 1)), 1e-12));
}

TEST(BezierCut, SlabThroughIntermediarySurfacesOnly) {
  // The same plate with the local repair switched off: the paper's intermediary surfaces alone.
  SurfaceMesh m = testmesh::Box({-0.15, -0.6, -1}, {0.15, 0.6, 1}, 0.05);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.01; });
  const double h = 0.52;
  Curve U = Line({-1, -1, h}, {1, -1, h}), V = Line({-1, -1, h}, {-1, 1, h});
  BezierCutOptions o;
  o.localRepair = false;
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, o, r);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_GT(r.intermediarySteps, 1);
  EXPECT_TRUE(ContractHeld(CheckContract(m, r, U, V, Vector3d(0, 0, 1)), 1e-12));
}

TEST(BezierCut, NothingOnTheSideMovesNothing) {
  SurfaceMesh m = testmesh::Icosphere(2);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.3; });
  Curve U = Line({-1.5, -1.5, 1.2}, {1.5, -1.5, 1.2}),
        V = Line({-1.5, -1.5, 1.2}, {-1.5, 1.5, 1.2});
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, {}, r);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(r.numMoved, 0);
  EXPECT_FALSE(r.warnings.empty());
  EXPECT_EQ(std::memcmp(r.points.data(), m.points.data(), sizeof(double) * 3 * m.numPoints()), 0);
}

// The default curves over a cap ROI: a plane normal to +z between the ROI boundary's top and the
// pole, covering the ROI across, whose Cut moves only interior ROI vertices above it.
TEST(BezierCut, DefaultCurvesCutTheCapClearOfTheBoundary) {
  SurfaceMesh m = testmesh::Icosphere(4);
  ROIResult roi = RoiWhere(m, [](const Vector3d& p) { return p.z() > 0.3; });
  Curve U, V;
  ASSERT_TRUE(DefaultCutCurves(m.points, roi.mask, roi.boundary, U, V));
  ASSERT_EQ(U.size(), 4u);
  ASSERT_EQ(V.size(), 4u);
  EXPECT_EQ(U[0], V[0]);
  const double h = U[0].z();
  double boundaryTop = -1.0;
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    if (roi.boundary[i])
      boundaryTop = std::max(boundaryTop, m.points(i, 2));
  EXPECT_GT(h, boundaryTop);
  EXPECT_LT(h, 1.0);
  for (const Vector3d& p : U)
    EXPECT_DOUBLE_EQ(p.z(), h);
  for (const Vector3d& p : V)
    EXPECT_DOUBLE_EQ(p.z(), h);
  EXPECT_GT((U[3] - U[0]).cross(V[3] - V[0]).z(), 0.0); // normal along +z: the pole is cut
  BezierCutResult r;
  Status s = BezierCut(m, roi.mask, roi.boundary, U, V, {}, r);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_GT(r.numMoved, 0);
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    if (r.moved[i]) {
      EXPECT_TRUE(roi.mask[i] && !roi.boundary[i]) << "vertex " << i;
      EXPECT_NEAR(r.points(i, 2), h, 1e-12);
    }
  // Nothing to cut: an ROI without extent.
  SurfaceMesh point;
  point.points = RowVectors3d::Zero(1, 3);
  EXPECT_FALSE(DefaultCutCurves(point.points, {1}, {0}, U, V));
}

// The local repair on a tangle it cannot undo (found by FuzzBezierCut: a fill through the side of
// a box whose ROI boundary lies on the fill side). Its untangling sweeps used to run to their
// limits, hundreds of vertex searches that changed nothing; they must stop once they stall.
TEST(CutMapping, LocalRepairStopsWhenUntanglingStalls) {
  const SurfaceMesh m = testmesh::Box({-8, -6, -4}, {8, 6, 4}, 4.0);
  ASSERT_EQ(m.numPoints(), 54);
  std::vector<std::uint8_t> selected(54, 1);
  for (int i : {14, 15, 17, 18, 19, 20, 21, 22, 23, 30})
    selected[std::size_t(i)] = 0;
  ROIResult roi;
  ASSERT_TRUE(ComputeROI(m, selected, roi));
  const Curve U = {{-18.96875, -10.09375, -4.84375},
                   {-8.6354166666666679, -4.875, -6.9375},
                   {-8.6770833333333339, -6.625, -8.5625},
                   {-1.4375, -9.5, -4.46875}};
  const Curve V = {{-18.96875, -10.09375, -4.84375},
                   {-18.5625, -0.60416666666666696, -4.71875},
                   {-20.9375, 1.2916666666666661, -7.84375},
                   {-21.65625, 9.15625, -7.59375}};
  BezierSurface surface;
  ASSERT_TRUE(BezierSurface::Create(U, V, /*flipNormal=*/true, surface));
  // What BezierCut hands the mapping for a fill: ROI vertices inside the patch behind S move.
  const Eigen::Index n = m.numPoints();
  std::vector<std::uint8_t> moved(std::size_t(n), 0);
  std::vector<Eigen::Vector2d> foot(std::size_t(n), Eigen::Vector2d::Zero());
  std::vector<std::vector<std::int64_t>> neighbours(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!roi.mask[std::size_t(i)])
      continue;
    const SurfaceProjection p = surface.project(m.points.row(i).transpose());
    foot[std::size_t(i)] = Eigen::Vector2d(p.u, p.v);
    moved[std::size_t(i)] = p.inside && p.signedDistance < 0 && !roi.boundary[std::size_t(i)];
  }
  for (std::size_t c = 0; c + 1 < m.offsets.size(); ++c)
    for (std::int64_t k = m.offsets[c]; k < m.offsets[c + 1]; ++k) {
      const std::int64_t a = m.connectivity[std::size_t(k)];
      const std::int64_t b =
          m.connectivity[std::size_t(k + 1 < m.offsets[c + 1] ? k + 1 : m.offsets[c])];
      neighbours[std::size_t(a)].push_back(b);
      neighbours[std::size_t(b)].push_back(a);
    }
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  CutMappingOptions options;
  options.localRepair = true;
  options.maxRelaxIterations = 1;
  options.stepSchedules = {};
  const CutMapping mapping =
      MapCutOntoSurface(surface, m, FanTriangles(m), neighbours, moved, foot, options);
  EXPECT_FALSE(mapping.ok);
  EXPECT_GT(mapping.repairVertexSearches, 0);
  // 452 searches when the sweeps ran to their limits.
  EXPECT_LE(mapping.repairVertexSearches, 200) << mapping.repairVertexSearches;
}
