// SPDX-License-Identifier: BSD-3-Clause
// Osteotomy Core: the rigid move, its composition and packing, the cut's sides and pieces, and the
// bookkeeping of MoveSegment (cumulative displacement, segment ids, transforms, errors).
#include "Osteotomy/CutPlanes.h"
#include "Osteotomy/Osteotomy.h"
#include "Osteotomy/SegmentTransform.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace faceplan;

namespace {

// A closed triangulated sphere (UV grid), centre c, radius r: nu x nv grid plus two poles.
void AppendSphere(SurfaceMesh& mesh, const Eigen::Vector3d& c, double r, int nu = 12, int nv = 8) {
  const std::int64_t base = mesh.numPoints();
  std::vector<Eigen::Vector3d> pts;
  pts.push_back(c + Eigen::Vector3d(0, 0, r));
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
      pts.push_back(c + r * Eigen::Vector3d(std::sin(th) * std::cos(ph),
                                            std::sin(th) * std::sin(ph), std::cos(th)));
    }
  pts.push_back(c - Eigen::Vector3d(0, 0, r));
  RowVectors3d all(base + static_cast<Eigen::Index>(pts.size()), 3);
  if (base > 0)
    all.topRows(base) = mesh.points;
  for (std::size_t k = 0; k < pts.size(); ++k)
    all.row(base + static_cast<Eigen::Index>(k)) = pts[k].transpose();
  mesh.points = all;
  auto ring = [&](int j, int i) { return base + 1 + (j - 1) * nu + (i % nu); };
  const std::int64_t south = base + static_cast<std::int64_t>(pts.size()) - 1;
  for (int i = 0; i < nu; ++i)
    mesh.addCell({base, ring(1, i), ring(1, i + 1)});
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      mesh.addCell({ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)});
      mesh.addCell({ring(j, i), ring(j + 1, i + 1), ring(j, i + 1)});
    }
  for (int i = 0; i < nu; ++i)
    mesh.addCell({south, ring(nv - 1, i + 1), ring(nv - 1, i)});
}

// Two spheres: the one at x = +5 is the segment (moves), the one at x = -5 stays.
OsteotomyBone TwoPieceBone() {
  OsteotomyBone bone;
  AppendSphere(bone.mesh, Eigen::Vector3d(-5, 0, 0), 2.0);
  const Eigen::Index fixedCount = bone.mesh.numPoints();
  AppendSphere(bone.mesh, Eigen::Vector3d(5, 1, 0), 2.0);
  const Eigen::Index n = bone.mesh.numPoints();
  bone.displacement = RowVectors3d::Zero(n, 3);
  bone.segmentId.assign(static_cast<std::size_t>(n), 0);
  bone.roiMask.assign(static_cast<std::size_t>(n), 0);
  bone.moves.assign(static_cast<std::size_t>(n), 0);
  for (Eigen::Index i = fixedCount; i < n; ++i)
    bone.moves[static_cast<std::size_t>(i)] = 1;
  return bone;
}

Eigen::Matrix3d Rot(double deg, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, axis).toRotationMatrix();
}

Eigen::Vector3d Undeformed(const OsteotomyResult& r, Eigen::Index i) {
  return (r.points.row(i) - r.displacement.row(i)).transpose();
}

} // namespace

TEST(OsteotomyTransform, RotationOrderIsXThenYThenZAboutThePivot) {
  SegmentMove move;
  move.rotationDegrees = Eigen::Vector3d(30, -50, 70);
  move.translation = Eigen::Vector3d(1, -2, 3);
  move.pivot = Eigen::Vector3d(4, 5, -6);
  AffineMap m;
  ASSERT_TRUE(RigidMotion(move, m));
  const Eigen::Matrix3d expected = Rot(70, Eigen::Vector3d::UnitZ()) *
                                   Rot(-50, Eigen::Vector3d::UnitY()) *
                                   Rot(30, Eigen::Vector3d::UnitX());
  // Step by step: rotate about X, then the result about Y, then about Z.
  const Eigen::Vector3d x(0.3, -1.2, 2.0);
  Eigen::Vector3d y = x - move.pivot;
  y = Rot(30, Eigen::Vector3d::UnitX()) * y;
  y = Rot(-50, Eigen::Vector3d::UnitY()) * y;
  y = Rot(70, Eigen::Vector3d::UnitZ()) * y;
  y += move.pivot + move.translation;
  EXPECT_LT((Apply(m, x) - y).norm(), 1e-12);
  EXPECT_LT((m.leftCols<3>() - expected).norm(), 1e-14);
  EXPECT_LT((Apply(m, move.pivot) - (move.pivot + move.translation)).norm(), 1e-12);
  EXPECT_NEAR(m.leftCols<3>().determinant(), 1.0, 1e-14);
  EXPECT_LT((m.leftCols<3>().transpose() * m.leftCols<3>() - Eigen::Matrix3d::Identity()).norm(),
            1e-14);
}

TEST(OsteotomyTransform, NonFiniteMoveIsAnError) {
  for (int which = 0; which < 3; ++which) {
    SegmentMove move;
    (which == 0 ? move.translation : which == 1 ? move.rotationDegrees : move.pivot)(1) = NAN;
    AffineMap m;
    const Status s = RigidMotion(move, m);
    EXPECT_FALSE(s);
    EXPECT_NE(s.message.find("not finite"), std::string::npos) << s.message;
  }
  SegmentMove huge;
  huge.translation.x() = 1e308;
  huge.pivot.x() = 1e308;
  AffineMap m;
  EXPECT_FALSE(RigidMotion(huge, m)); // pivot + translation overflows
}

TEST(OsteotomyTransform, ComposeAndPacking) {
  SegmentMove a, b;
  a.rotationDegrees = Eigen::Vector3d(10, 20, 30);
  a.translation = Eigen::Vector3d(1, 2, 3);
  b.rotationDegrees = Eigen::Vector3d(-15, 5, 45);
  b.pivot = Eigen::Vector3d(2, 0, 1);
  AffineMap ma, mb;
  ASSERT_TRUE(RigidMotion(a, ma));
  ASSERT_TRUE(RigidMotion(b, mb));
  const Eigen::Vector3d x(1, -1, 0.5);
  EXPECT_LT((Apply(Compose(ma, mb), x) - Apply(ma, Apply(mb, x))).norm(), 1e-12);
  const std::vector<double> packed = PackSegmentTransforms({ma, mb});
  ASSERT_EQ(packed.size(), 24u);
  EXPECT_EQ(packed[3], ma(0, 3)); // row-major [R | t]
  EXPECT_EQ(packed[4], ma(1, 0));
  EXPECT_EQ(packed[12 + 11], mb(2, 3));
  const auto back = UnpackSegmentTransforms(packed, 3);
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[0], ma);
  EXPECT_EQ(back[1], mb);
  EXPECT_FALSE(IsFinite(back[2])); // missing -> not rigid
}

TEST(OsteotomyCut, PlaneValidation) {
  std::vector<CutPlane> none;
  EXPECT_FALSE(NormalizeCutPlanes(none));
  std::vector<CutPlane> zero(1);
  zero[0].normal.setZero();
  EXPECT_NE(NormalizeCutPlanes(zero).message.find("zero-length normal"), std::string::npos);
  std::vector<CutPlane> nan(2);
  nan[1].origin.y() = NAN;
  EXPECT_NE(NormalizeCutPlanes(nan).message.find("cut plane 2"), std::string::npos);
  std::vector<CutPlane> ok(1);
  ok[0].normal = Eigen::Vector3d(0, 3, 4);
  ASSERT_TRUE(NormalizeCutPlanes(ok));
  EXPECT_NEAR(ok[0].normal.norm(), 1.0, 1e-15);
}

// Normals whose squared length underflows or overflows (found by FuzzOsteotomy) still give unit
// normals in their direction; a normal of denormals is not zero either.
TEST(OsteotomyCut, TinyAndHugeNormalsBecomeUnitNormals) {
  for (const double scale : {1e-160, 1e-200, 4.9e-324, 1e160, 1e300}) {
    std::vector<CutPlane> planes(1);
    planes[0].normal = Eigen::Vector3d(0, 3, 4) * scale;
    ASSERT_TRUE(NormalizeCutPlanes(planes)) << scale;
    EXPECT_NEAR(planes[0].normal.norm(), 1.0, 1e-15) << scale;
    if (scale > 1e-300)
      EXPECT_NEAR(planes[0].normal.z(), 0.8, 1e-15) << scale;
  }
}

TEST(OsteotomyCut, SidesAndInsideOut) {
  RowVectors3d p(4, 3);
  p << -2, 0, 0, -1, 0, 0, 1, 0, 0, 2, 0, 0;
  std::vector<CutPlane> planes(1);
  std::vector<std::uint8_t> side;
  ASSERT_TRUE(ClassifyCutSides(p, planes, false, side));
  EXPECT_EQ(side, (std::vector<std::uint8_t>{0, 0, 1, 1}));
  ASSERT_TRUE(ClassifyCutSides(p, planes, true, side));
  EXPECT_EQ(side, (std::vector<std::uint8_t>{1, 1, 0, 0}));
  planes[0].origin.x() = 5;
  Status s = ClassifyCutSides(p, planes, false, side);
  EXPECT_NE(s.message.find("no vertex of the bone on the moving side"), std::string::npos)
      << s.message;
  s = ClassifyCutSides(p, planes, true, side);
  EXPECT_NE(s.message.find("no vertex of the bone on the fixed side"), std::string::npos)
      << s.message;
}

TEST(OsteotomyCut, ConvexPiecesPartitionSpace) {
  std::vector<CutPlane> planes(2);
  planes[0].origin = Eigen::Vector3d(0.1, 0, 0);
  planes[0].normal = Eigen::Vector3d(1, 0.2, 0);
  planes[1].origin = Eigen::Vector3d(0, -0.3, 0.2);
  planes[1].normal = Eigen::Vector3d(0.3, 1, -0.5);
  ASSERT_TRUE(NormalizeCutPlanes(planes));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  for (bool insideOut : {false, true}) {
    const auto pieces = ConvexPiecesOfCut(planes, insideOut);
    ASSERT_EQ(pieces.size(), 3u);
    for (int k = 0; k < 2000; ++k) {
      const Eigen::Vector3d x(u(rng), u(rng), u(rng));
      int inside = 0;
      bool moves = false;
      for (const auto& piece : pieces) {
        bool in = true;
        for (const auto& h : piece.bounds)
          in = in && h.normal.dot(x - h.origin) > 0.0;
        if (in) {
          ++inside;
          moves = piece.moves;
        }
      }
      ASSERT_EQ(inside, 1) << "pieces overlap or leave a gap at " << x.transpose();
      ASSERT_EQ(moves, OnSegmentSide(planes, insideOut, x));
    }
  }
}

TEST(OsteotomyCut, PlaneBoxSection) {
  const std::array<double, 6> box = {0, 2, 0, 4, 0, 6};
  CutPlane mid;
  mid.origin = Eigen::Vector3d(1, 2, 3);
  mid.normal = Eigen::Vector3d(0, 0, 1);
  auto quad = PlaneBoxSection(mid, box);
  ASSERT_EQ(quad.size(), 4u);
  double area = 0.0;
  for (std::size_t k = 0; k < quad.size(); ++k) {
    EXPECT_NEAR(quad[k].z(), 3.0, 1e-14);
    area += 0.5 *
            (quad[k] - mid.origin).cross(quad[(k + 1) % quad.size()] - mid.origin).dot(mid.normal);
  }
  EXPECT_NEAR(std::abs(area), 8.0, 1e-12); // ordered corners: the 2 x 4 rectangle
  CutPlane corner;
  corner.origin = Eigen::Vector3d(1, 0, 0);
  corner.normal =
      Eigen::Vector3d(1, 0.5, 1.0 / 3.0).normalized(); // through (1,0,0), (0,2,0), (0,0,3)
  EXPECT_EQ(PlaneBoxSection(corner, box).size(), 3u);
  CutPlane away;
  away.origin = Eigen::Vector3d(0, 0, 10);
  away.normal = Eigen::Vector3d(0, 0, 1);
  EXPECT_TRUE(PlaneBoxSection(away, box).empty());
}

TEST(OsteotomyMoveSegment, MovesOnlyTheSegmentRigidly) {
  const OsteotomyBone bone = TwoPieceBone();
  OsteotomyMove request;
  request.move.translation = Eigen::Vector3d(5, 0, -1);
  request.move.rotationDegrees = Eigen::Vector3d(0, 0, 12);
  OsteotomyResult r;
  ASSERT_TRUE(MoveSegment(bone, request, r)) << r.newSegmentId;
  EXPECT_EQ(r.newSegmentId, 1);
  ASSERT_EQ(r.segmentTransforms.size(), 12u);
  AffineMap t = UnpackSegmentTransforms(r.segmentTransforms, 1)[0];
  // The default pivot is the segment's centroid (the moving sphere's centre): it only translates.
  EXPECT_LT((r.pivot - Eigen::Vector3d(5, 1, 0)).norm(), 1e-12);
  EXPECT_LT((Apply(t, r.pivot) - (r.pivot + request.move.translation)).norm(), 1e-12);
  for (Eigen::Index i = 0; i < bone.mesh.numPoints(); ++i) {
    const std::size_t ui = static_cast<std::size_t>(i);
    const Eigen::Vector3d before = bone.mesh.points.row(i), after = r.points.row(i);
    EXPECT_LT((Undeformed(r, i) - before).norm(), 1e-12);
    if (bone.moves[ui]) {
      EXPECT_EQ(r.segmentId[ui], 1);
      EXPECT_EQ(r.roiMask[ui], 1);
      EXPECT_LT((Apply(t, before) - after).norm(), 1e-12);
    } else {
      EXPECT_EQ(r.segmentId[ui], 0);
      EXPECT_EQ(r.roiMask[ui], 0);
      EXPECT_EQ(before, after);
      EXPECT_EQ(r.displacement.row(i).norm(), 0.0);
    }
  }
  EXPECT_EQ(r.segmentNotes, std::vector<std::string>{""});
}

TEST(OsteotomyMoveSegment, ChainedOsteotomiesCompose) {
  OsteotomyBone bone = TwoPieceBone();
  OsteotomyMove first;
  first.move.translation = Eigen::Vector3d(1, 2, 3);
  first.move.rotationDegrees = Eigen::Vector3d(5, 10, 15);
  OsteotomyResult r1;
  ASSERT_TRUE(MoveSegment(bone, first, r1));
  // Second osteotomy: the upper half of the moved segment moves again, about a given pivot.
  OsteotomyBone bone2 = bone;
  bone2.mesh.points = r1.points;
  bone2.displacement = r1.displacement;
  bone2.segmentId = r1.segmentId;
  bone2.roiMask = r1.roiMask;
  bone2.segmentTransforms = r1.segmentTransforms;
  bone2.segmentNotes = r1.segmentNotes;
  const double zMid = r1.pivot.z() + first.move.translation.z();
  for (Eigen::Index i = 0; i < r1.points.rows(); ++i)
    bone2.moves[static_cast<std::size_t>(i)] =
        r1.segmentId[static_cast<std::size_t>(i)] == 1 && r1.points(i, 2) > zMid;
  OsteotomyMove second;
  second.pivotMode = PivotMode::Custom;
  second.move.pivot = Eigen::Vector3d(0, 0, 1);
  second.move.rotationDegrees = Eigen::Vector3d(-20, 0, 7);
  second.move.translation = Eigen::Vector3d(0, -1, 0);
  OsteotomyResult r2;
  ASSERT_TRUE(MoveSegment(bone2, second, r2));
  EXPECT_EQ(r2.newSegmentId, 2);
  ASSERT_EQ(r2.segmentTransforms.size(), 24u);
  const auto maps = UnpackSegmentTransforms(r2.segmentTransforms, 2);
  EXPECT_EQ(maps[0], UnpackSegmentTransforms(r1.segmentTransforms, 1)[0]);
  int counts[3] = {0, 0, 0};
  for (Eigen::Index i = 0; i < r2.points.rows(); ++i) {
    const int s = r2.segmentId[static_cast<std::size_t>(i)];
    ++counts[s];
    const Eigen::Vector3d x0 = bone.mesh.points.row(i), p = r2.points.row(i);
    EXPECT_LT((Undeformed(r2, i) - x0).norm(), 1e-12); // Displacement is cumulative
    if (s > 0) {
      EXPECT_LT((Apply(maps[s - 1], x0) - p).norm(), 1e-11) << "segment " << s;
    }
  }
  EXPECT_GT(counts[1], 0);
  EXPECT_GT(counts[2], 0);
  EXPECT_EQ(r2.segmentNotes, (std::vector<std::string>{"", ""}));
}

TEST(OsteotomyMoveSegment, NonRigidInputKeepsExactDisplacementButNoTransform) {
  OsteotomyBone bone = TwoPieceBone();
  // A reshaping before the osteotomy (as BezierCut does): points pushed along x by x^2 / 50.
  for (Eigen::Index i = 0; i < bone.mesh.numPoints(); ++i) {
    const double dx = bone.mesh.points(i, 0) * bone.mesh.points(i, 0) / 50.0;
    bone.displacement(i, 0) = dx;
    bone.mesh.points(i, 0) += dx;
  }
  const RowVectors3d undeformed = bone.mesh.points - bone.displacement;
  OsteotomyMove request;
  request.move.translation = Eigen::Vector3d(0, 0, 4);
  OsteotomyResult r;
  ASSERT_TRUE(MoveSegment(bone, request, r));
  ASSERT_EQ(r.segmentTransforms.size(), 12u);
  for (double v : r.segmentTransforms)
    EXPECT_TRUE(std::isnan(v));
  ASSERT_EQ(r.segmentNotes.size(), 1u);
  EXPECT_NE(r.segmentNotes[0].find("not moved rigidly"), std::string::npos) << r.segmentNotes[0];
  for (Eigen::Index i = 0; i < r.points.rows(); ++i) {
    EXPECT_LT((Undeformed(r, i) - undeformed.row(i).transpose()).norm(), 1e-12);
    if (bone.moves[static_cast<std::size_t>(i)]) {
      EXPECT_LT((r.points.row(i) - bone.mesh.points.row(i) - Eigen::RowVector3d(0, 0, 4)).norm(),
                1e-12);
    }
  }
}

TEST(OsteotomyMoveSegment, ErrorsNameTheProblem) {
  auto message = [](OsteotomyBone bone, OsteotomyMove move = OsteotomyMove()) {
    OsteotomyResult r;
    const Status s = MoveSegment(bone, move, r);
    EXPECT_FALSE(s);
    return s.message;
  };
  OsteotomyBone quad = TwoPieceBone();
  quad.mesh.offsets.back() -= 1; // the last cell loses a point: a segment of two
  quad.mesh.connectivity.pop_back();
  EXPECT_NE(message(quad).find("not a triangle"), std::string::npos);
  OsteotomyBone nanPoint = TwoPieceBone();
  nanPoint.mesh.points(3, 1) = NAN;
  EXPECT_NE(message(nanPoint).find("NaN or infinite coordinate"), std::string::npos);
  OsteotomyBone nothing = TwoPieceBone();
  std::fill(nothing.moves.begin(), nothing.moves.end(), 0);
  EXPECT_NE(message(nothing).find("moving side"), std::string::npos);
  OsteotomyBone everything = TwoPieceBone();
  std::fill(everything.moves.begin(), everything.moves.end(), 1);
  EXPECT_NE(message(everything).find("fixed side"), std::string::npos);
  OsteotomyMove nanMove;
  nanMove.move.rotationDegrees.z() = INFINITY;
  EXPECT_NE(message(TwoPieceBone(), nanMove).find("not finite"), std::string::npos);
  OsteotomyBone empty;
  EXPECT_NE(message(empty).find("no points"), std::string::npos);
}
