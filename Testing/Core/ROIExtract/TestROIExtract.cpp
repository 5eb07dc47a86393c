// SPDX-License-Identifier: BSD-3-Clause
// ROIExtract contract: ROIMask is the selection, ROIBoundary marks ROI vertices with a non-ROI
// neighbour along a cell edge; malformed input gives an error and an empty result.
#include "ROIExtract/DefaultRegion.h"
#include "ROIExtract/ROIExtract.h"
#include "Support/FaceplanTestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

using namespace faceplan;

namespace {

// Reference: edges collected independently from the triangles.
std::vector<std::uint8_t> ReferenceBoundary(const SurfaceMesh& m,
                                            const std::vector<std::uint8_t>& sel) {
  std::set<std::pair<std::int64_t, std::int64_t>> edges;
  for (std::int64_t c = 0; c < m.numCells(); ++c) {
    const std::int64_t* ids = m.cell(c);
    const std::int64_t n = m.cellSize(c);
    for (std::int64_t k = 0; k < n; ++k)
      edges.insert(std::minmax(ids[k], ids[(k + 1) % n]));
  }
  std::vector<std::uint8_t> b(sel.size(), 0);
  for (auto [a, c] : edges) {
    if (sel[a] && !sel[c])
      b[a] = 1;
    if (sel[c] && !sel[a])
      b[c] = 1;
  }
  return b;
}

} // namespace

TEST(ROIExtract, SphereCapMaskAndBoundary) {
  SurfaceMesh m = testmesh::Icosphere(3);
  std::vector<std::uint8_t> sel(m.numPoints());
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    sel[i] = m.points(i, 2) > 0.6;
  ROIResult r;
  Status s = ComputeROI(m, sel, r);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(r.mask.size(), sel.size());
  EXPECT_EQ(r.mask, sel);
  EXPECT_EQ(r.boundary, ReferenceBoundary(m, sel));
  std::int64_t nb = 0, nroi = 0;
  for (std::size_t i = 0; i < sel.size(); ++i) {
    nb += r.boundary[i];
    nroi += sel[i];
    if (r.boundary[i])
      EXPECT_EQ(r.mask[i], 1) << "boundary vertex outside the ROI: " << i;
  }
  EXPECT_GT(nb, 0);
  EXPECT_LT(nb, nroi); // a cap has interior vertices
  EXPECT_EQ(r.numROI, nroi);
  EXPECT_EQ(r.numBoundary, nb);
}

TEST(ROIExtract, FromIdsEqualsSelection) {
  SurfaceMesh m = testmesh::PlaneGrid(8, 8);
  std::vector<std::int64_t> ids;
  std::vector<std::uint8_t> sel(m.numPoints(), 0);
  for (Eigen::Index i = 0; i < m.numPoints(); ++i)
    if ((m.points.row(i) - Eigen::RowVector3d(0.5, 0.5, 0)).norm() < 0.3) {
      ids.push_back(i);
      sel[i] = 1;
    }
  ROIResult a, b;
  ASSERT_TRUE(ComputeROIFromIds(m, ids, a).ok);
  ASSERT_TRUE(ComputeROI(m, sel, b).ok);
  EXPECT_EQ(a.mask, b.mask);
  EXPECT_EQ(a.boundary, b.boundary);
  EXPECT_EQ(a.boundary, ReferenceBoundary(m, sel));
}

TEST(ROIExtract, PolygonsAndLines) {
  // A quad 0-1-2-3 and a line 3-4; ROI = {0, 1, 2, 4}.
  SurfaceMesh m;
  m.points.resize(5, 3);
  m.points << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 2, 0;
  m.addCell({0, 1, 2, 3});
  m.addCell({3, 4});
  ROIResult r;
  ASSERT_TRUE(ComputeROI(m, {1, 1, 1, 0, 1}, r).ok);
  // 0-3 and 2-3 are quad edges (0-2 is not an edge); 4-3 is the line.
  EXPECT_EQ(r.boundary, (std::vector<std::uint8_t>{1, 0, 1, 0, 1}));
}

TEST(ROIExtract, WholeMeshHasNoBoundary) {
  SurfaceMesh m = testmesh::Icosphere(1);
  ROIResult r;
  ASSERT_TRUE(ComputeROI(m, std::vector<std::uint8_t>(m.numPoints(), 1), r).ok);
  for (auto b : r.boundary)
    EXPECT_EQ(b, 0);
}

TEST(ROIExtract, Errors) {
  SurfaceMesh m = testmesh::PlaneGrid(2, 2);
  ROIResult r;
  Status s = ComputeROI(m, std::vector<std::uint8_t>(3, 1), r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("entries"), std::string::npos) << s.message;
  EXPECT_TRUE(r.mask.empty());

  s = ComputeROIFromIds(m, {0, 99}, r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("99"), std::string::npos) << s.message;

  SurfaceMesh bad = m;
  bad.connectivity[0] = 1000;
  s = ComputeROI(bad, std::vector<std::uint8_t>(bad.numPoints(), 1), r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("out of range"), std::string::npos) << s.message;

  bad = m;
  bad.points(2, 1) = std::nan("");
  s = ComputeROI(bad, std::vector<std::uint8_t>(bad.numPoints(), 1), r);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("non-finite"), std::string::npos) << s.message;
}

// Where a new ROI sphere starts: on the most anterior point (smallest x in the face frame), with a
// fifth of the largest extent as radius; no start for no points, a zero extent or a NaN point.
TEST(ROIExtract, DefaultSphereOnTheMostAnteriorPoint) {
  RowVectors3d p(4, 3);
  p << 10, 0, 0, 2, 5, 1, 7, -3, 40, 30, 1, 2;
  Eigen::Vector3d centre;
  double radius = -1.0;
  ASSERT_TRUE(DefaultROISphere(p, centre, radius));
  EXPECT_EQ(centre, Eigen::Vector3d(2, 5, 1));
  EXPECT_DOUBLE_EQ(radius, kDefaultROIRadiusFraction * 40.0); // the z extent, 0..40
  EXPECT_FALSE(DefaultROISphere(RowVectors3d(0, 3), centre, radius));
  EXPECT_FALSE(DefaultROISphere(RowVectors3d::Ones(3, 3), centre, radius));
  p(2, 1) = std::nan("");
  EXPECT_FALSE(DefaultROISphere(p, centre, radius));
}
