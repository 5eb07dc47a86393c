// SPDX-License-Identifier: BSD-3-Clause
// TissueModelFromCT with CGAL Mesh_3 on a labelled shell around a bone ball (the analytic hollow
// sphere's sizes): geometry, orientation, quality, boundary distance, reproducibility, the image
// frame, and the deformation against the analytic solution. Skipped when built without CGAL.
#include "CondensedFEM/CondensedFEM.h"
#include "Mesh/TetGeometry.h"
#include "Support/AnalyticHollowSphere.h"
#include "SyntheticImages.h"
#include "TissueModelFromCT/TissueModel.h"
#ifdef FACEPLAN_HAVE_CGAL
#include "Copyleft/CGAL/LabeledImageMesher.h"
#endif

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <map>
#include <set>

using namespace faceplan;

namespace {

#ifdef FACEPLAN_HAVE_CGAL
const LabelMesher kMesher = cgal::MeshLabeledImage;
#define REQUIRE_CGAL()
#else
const LabelMesher kMesher;
#define REQUIRE_CGAL() GTEST_SKIP() << "built without CGAL (FACEPLAN_ENABLE_CGAL=OFF)"
#endif

// Voxels fine enough that the labelled interface lies within half a voxel (0.0125) of the spheres.
constexpr double kVoxel = 0.025;

const LabelImage& Shell() {
  static const LabelImage image = testimages::ShellAroundBall(1.0, 2.0, kVoxel, 2.2);
  return image;
}

TissueModelParameters Parameters(double cellSize, double surfaceDistance) {
  TissueModelParameters p;
  p.meshing.cellSize = cellSize;
  p.meshing.surfaceDistance = surfaceDistance;
  p.meshing.sliverBound = 10.0;
  p.meshing.seed = 7;
  p.labelling.minimumBoneComponentVolume = 0.01; // the defaults are for a head in mm
  p.labelling.maximumBoneHoleVolume = 0.1;
  return p;
}

double Volume(const TetMesh& mesh) {
  double v = 0.0;
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k)
      c.row(k) = mesh.points.row(mesh.tets(e, k));
    v += TetVolume(c);
  }
  return v;
}

// Largest distance of a facet's corners, edge midpoints and centroid from the sphere of `radius`.
double LargestSphereDistance(const TissueModel& m, const Facets& f, double radius,
                             const Eigen::Vector3d& centre) {
  double largest = 0.0;
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = m.tissue.points.row(f(t, 0)), b = m.tissue.points.row(f(t, 1)),
                          c = m.tissue.points.row(f(t, 2));
    for (const Eigen::Vector3d& p :
         {a, b, c, Eigen::Vector3d(0.5 * (a + b)), Eigen::Vector3d(0.5 * (b + c)),
          Eigen::Vector3d(0.5 * (c + a)), Eigen::Vector3d((a + b + c) / 3.0)})
      largest = std::max(largest, std::abs((p - centre).norm() - radius));
  }
  return largest;
}

} // namespace

TEST(TissueModelMeshing, ShellVolumeBoundaryAndQuality) {
  REQUIRE_CGAL();
  const double surfaceDistance = 0.025;
  const TissueModelParameters p = Parameters(0.3, surfaceDistance);
  TissueModel m;
  const Status s = BuildTissueModelFromLabels(Shell(), p, kMesher, m);
  ASSERT_TRUE(s.ok) << s.message;
  for (const std::string& w : s.warnings)
    ADD_FAILURE() << "warning: " << w;

  const double exact = 4.0 / 3.0 * M_PI * (8.0 - 1.0);
  const double volume = Volume(m.tissue);
  std::printf("tets %lld, volume %.5f (exact %.5f, %+.3f %%), boundary distance %.4f, worst "
              "dihedral %.2f deg, "
              "smallest mean ratio %.3f\n",
              (long long)m.tissue.numTets(), volume, exact, 100.0 * (volume - exact) / exact,
              m.boundaryDistance.largest, m.quality.worstDihedralAngle,
              m.quality.smallestMeanRatio);
  EXPECT_LT(std::abs(volume - exact), 0.01 * exact);
  // The budget's estimate does not undercount the first attempt (smooth spheres need fewer
  // boundary facets than the voxelised anatomy it is calibrated on, so it overcounts here).
  ASSERT_FALSE(m.attemptCells.empty());
  EXPECT_GE(m.estimatedCells, double(m.attemptCells.front()));
  // Against the labelled interface (Core's measure) and against the analytic spheres.
  EXPECT_LE(m.boundaryDistance.largest, surfaceDistance);
  EXPECT_EQ(m.boundaryDistance.notFound, 0);
  EXPECT_LE(LargestSphereDistance(m, m.skinFacets, 2.0, Eigen::Vector3d::Zero()), surfaceDistance);
  EXPECT_LE(LargestSphereDistance(m, m.boneFacets, 1.0, Eigen::Vector3d::Zero()), surfaceDistance);
  // Every tetrahedron positive, the quality bound met.
  EXPECT_EQ(m.quality.nonPositive, 0);
  EXPECT_GT(m.quality.smallestVolume, 0.0);
  EXPECT_GE(m.quality.worstDihedralAngle, p.meshing.sliverBound);
  EXPECT_EQ(m.quality.belowDihedralBound, 0);
  // Closed surfaces: every facet edge shared by exactly two facets of the same surface.
  for (const Facets* f : {&m.skinFacets, &m.boneFacets}) {
    std::map<std::pair<int, int>, int> edges;
    for (Eigen::Index t = 0; t < f->rows(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int u = (*f)(t, k), v = (*f)(t, (k + 1) % 3);
        ++edges[{std::min(u, v), std::max(u, v)}];
      }
    for (const auto& e : edges)
      EXPECT_EQ(e.second, 2);
  }
}

TEST(TissueModelMeshing, SameSeedSameMesh) {
  REQUIRE_CGAL();
  const TissueModelParameters p = Parameters(0.8, 0.05);
  TissueModel first, second;
  ASSERT_TRUE(BuildTissueModelFromLabels(Shell(), p, kMesher, first).ok);
  ASSERT_TRUE(BuildTissueModelFromLabels(Shell(), p, kMesher, second).ok);
  ASSERT_EQ(first.tissue.numPoints(), second.tissue.numPoints());
  EXPECT_EQ(first.tissue.points, second.tissue.points);
  EXPECT_EQ(first.tissue.tets, second.tissue.tets);
}

TEST(TissueModelMeshing, ImageFrameIsHonoured) {
  REQUIRE_CGAL();
  // The same shell in an image rotated 30 degrees about an oblique axis and moved: the mesh
  // follows.
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d centre(10.0, -4.0, 7.0);
  const LabelImage moved = testimages::ShellAroundBall(1.0, 2.0, 0.05, 2.2, centre, rotation);
  TissueModel m;
  const Status s = BuildTissueModelFromLabels(moved, Parameters(0.8, 0.06), kMesher, m);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_LE(LargestSphereDistance(m, m.skinFacets, 2.0, centre), 0.06);
  EXPECT_LE(LargestSphereDistance(m, m.boneFacets, 1.0, centre), 0.06);
  EXPECT_EQ(m.quality.nonPositive, 0);
}

TEST(TissueModelMeshing, FromCTThroughLabelling) {
  REQUIRE_CGAL();
  TissueModel m;
  const Status s =
      BuildTissueModel(testimages::AsCT(testimages::ShellAroundBall(1.0, 2.0, 0.05, 2.2)),
                       Parameters(0.8, 0.06), kMesher, m);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_GT(m.tissue.numTets(), 0);
  EXPECT_GT(m.boneFacets.rows(), 0);
  EXPECT_GT(m.skinFacets.rows(), 0);
  EXPECT_LT(m.tissue.numTets(), m.meshedCells); // the bone's cells were dropped
}

TEST(TissueModelMeshing, CancelledBeforeRefinementStops) {
  REQUIRE_CGAL();
  std::atomic<bool> cancel(true);
  TissueModel m;
  const Status s = BuildTissueModelFromLabels(Shell(), Parameters(0.8, 0.05), kMesher, m, &cancel);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "cancelled");
}

// The shell meshed from its labels, then deformed by CondensedFEM: analytic radial displacement
// prescribed on the bone interface, free skin. The relative L2 error against the analytic solution
// must fall as CellSize shrinks (SurfaceDistance shrinks with it).
TEST(TissueModelMeshing, DeformationErrorFallsWithCellSize) {
  REQUIRE_CGAL();
  HollowSphere exact;
  std::vector<double> errors;
  for (double h : {0.8, 0.55, 0.4}) {
    TissueModel m;
    const Status built = BuildTissueModelFromLabels(Shell(), Parameters(h, h / 16.0), kMesher, m);
    ASSERT_TRUE(built.ok) << built.message;
    std::set<int> boneNodes;
    for (Eigen::Index t = 0; t < m.boneFacets.rows(); ++t)
      for (int k = 0; k < 3; ++k)
        boneNodes.insert(m.boneFacets(t, k));
    PrecomputeRequest request;
    request.mesh = m.tissue;
    request.materials = Materials::Uniform(exact.E, exact.nu);
    request.sets.constrained.assign(boneNodes.begin(), boneNodes.end());
    request.sets.movable = request.sets.constrained;
    for (Eigen::Index t = 0; t < m.skinFacets.rows(); ++t)
      request.sets.kept.push_back(m.skinFacets(t, 0));
    std::sort(request.sets.kept.begin(), request.sets.kept.end());
    request.sets.kept.erase(std::unique(request.sets.kept.begin(), request.sets.kept.end()),
                            request.sets.kept.end());
    request.options.method = SolveMethod::CachedFactor;
    std::shared_ptr<const CondensedSystem> system;
    const Status pre = Precompute(request, system);
    ASSERT_TRUE(pre.ok) << pre.message;
    SolveInput input;
    input.movableDisplacement.resize(Eigen::Index(request.sets.movable.size()), 3);
    for (std::size_t k = 0; k < request.sets.movable.size(); ++k)
      input.movableDisplacement.row(Eigen::Index(k)) =
          exact.displacement(m.tissue.points.row(request.sets.movable[k]).transpose()).transpose();
    input.recoverInterior = true;
    SolveResult result;
    const Status solved = Solve(*system, input, result);
    ASSERT_TRUE(solved.ok) << solved.message;
    double l2Exact = 0.0;
    errors.push_back(HollowSphereL2Error(m.tissue, result.allDisplacement, exact, l2Exact) /
                     l2Exact);
    std::printf("CellSize %.2f: %lld tets, relative L2 error %.3e\n", h,
                (long long)m.tissue.numTets(), errors.back());
  }
  for (std::size_t k = 1; k < errors.size(); ++k)
    EXPECT_LT(errors[k], errors[k - 1]) << "refinement " << k;
}
