// SPDX-License-Identifier: BSD-3-Clause
// The triangle box tree behind BezierCut's intersection checks: its candidates include every pair
// whose boxes are not apart, whatever the triangles' sizes and shapes, and a crossing far along a
// large triangle is found.
#include "BezierCut/MeshIntersection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace faceplan;

namespace {

void SetPoint(RowVectors3d& P, Eigen::Index i, double x, double y, double z) {
  P.row(i) << x, y, z;
}

} // namespace

TEST(MeshIntersection, TreeCandidatesHoldEveryPairWhoseBoxesAreNotApart) {
  // Triangles of mixed sizes (1e-3 to 1e3) and aspect ratios (slivers along each axis).
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int count = 400;
  RowVectors3d P(3 * count, 3);
  std::vector<Tri> tris;
  for (int t = 0; t < count; ++t) {
    const double size = std::pow(10.0, -3.0 + 6.0 * unit(random));
    const Eigen::RowVector3d corner(100 * unit(random), 100 * unit(random), 100 * unit(random));
    Eigen::RowVector3d stretch(1, 1, 1);
    stretch[t % 3] = t % 2 ? 1e-3 : 1.0;
    for (int k = 0; k < 3; ++k) {
      const Eigen::RowVector3d offset(unit(random), unit(random), unit(random));
      P.row(3 * t + k) = corner + size * offset.cwiseProduct(stretch);
    }
    tris.push_back(Tri{{3 * t, 3 * t + 1, 3 * t + 2}});
  }
  std::vector<std::int64_t> ids(tris.size());
  for (std::size_t t = 0; t < ids.size(); ++t)
    ids[t] = std::int64_t(t);
  const TriangleBoxTree tree(tris, P, ids);
  std::vector<std::int64_t> candidates;
  int pairsNotApart = 0;
  for (std::int64_t a = 0; a < count; ++a) {
    tree.candidates(a, candidates);
    EXPECT_TRUE(std::is_sorted(candidates.begin(), candidates.end()));
    for (std::int64_t b = 0; b < count; ++b) {
      if (TriangleBoxesApart(tris[a], tris[b], P))
        continue;
      ++pairsNotApart;
      EXPECT_TRUE(std::binary_search(candidates.begin(), candidates.end(), b))
          << "triangles " << a << " and " << b << " are not apart but not candidates";
    }
  }
  EXPECT_GT(pairsNotApart, 2 * count); // the check saw more than each triangle with itself
}

TEST(MeshIntersection, CrossingFarAlongALargeTriangleIsFound) {
  // A large fixed triangle (1000 units) and a small triangle (edge 1) that moves through it near
  // its far corner, hundreds of small-triangle sizes from the large one's box corner.
  RowVectors3d before(6, 3);
  SetPoint(before, 0, 0, 0, 0);
  SetPoint(before, 1, 1000, 0, 0);
  SetPoint(before, 2, 0, 1000, 0);
  SetPoint(before, 3, 700, 200, 0.5);
  SetPoint(before, 4, 701, 200, 0.5);
  SetPoint(before, 5, 700, 201, 1.5);
  RowVectors3d after = before;
  after.col(2).tail(3).array() -= 1.0; // the small triangle now spans z = -0.5 .. 0.5
  const std::vector<Tri> tris = {Tri{{0, 1, 2}}, Tri{{3, 4, 5}}};
  const std::vector<std::int64_t> crossing = NewIntersections(tris, before, after, {0, 1});
  EXPECT_EQ(crossing, (std::vector<std::int64_t>{0, 1}));
  EXPECT_TRUE(NewIntersections(tris, before, before, {0, 1}).empty());
}
