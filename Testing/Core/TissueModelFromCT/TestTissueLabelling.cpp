// SPDX-License-Identifier: BSD-3-Clause
// The CGAL-free parts of TissueModelFromCT: labelling, parameter checks, the cell budget, quality
// measures and the split of a labelled mesh into tissue, bone and skin.
#include "Mesh/MeshValidation.h"
#include "Support/ShellMeshGenerator.h"
#include "SyntheticImages.h"
#include "TissueModelFromCT/TissueModel.h"

#include <Eigen/Geometry>
#include <cmath>
#include <gtest/gtest.h>

using namespace faceplan;

namespace {

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// The defaults are in mm^3 for a head; this scene is a few units wide (0.1 voxels).
LabellingOptions SmallScene() {
  LabellingOptions o;
  o.minimumBoneComponentVolume = 0.01; // ten voxels
  o.maximumBoneHoleVolume = 0.1;
  return o;
}

CTImage ShellCT() {
  return testimages::AsCT(testimages::ShellAroundBall(1.0, 2.0, 0.1, 2.5));
}

} // namespace

TEST(TissueLabelling, ShellAroundBallIsLabelledAsDrawn) {
  const LabelImage drawn = testimages::ShellAroundBall(1.0, 2.0, 0.1, 2.5);
  LabelImage labels;
  LabellingSummary summary;
  const Status s = LabelTissue(testimages::AsCT(drawn), SmallScene(), labels, summary);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(labels.labels, drawn.labels);
  EXPECT_EQ(summary.bonePieces, 1);
  const double voxel = 0.1 * 0.1 * 0.1;
  EXPECT_NEAR(double(summary.softTissueVoxels) * voxel, 4.0 / 3.0 * M_PI * 7.0,
              0.05 * 4.0 / 3.0 * M_PI * 7.0);
}

TEST(TissueLabelling, CavitiesNoiseAndHolesAreHandled) {
  CTImage ct = ShellCT();
  const ImageGrid& g = ct.grid;
  auto at = [&](const Eigen::Vector3d& x) -> float& {
    const Eigen::Vector3d s = g.toScaled(x);
    return ct.hounsfield[g.index(int(std::lround(s[0] / g.spacing[0])),
                                 int(std::lround(s[1] / g.spacing[1])),
                                 int(std::lround(s[2] / g.spacing[2])))];
  };
  at({1.5, 0.0, 0.0}) = -1000.0f; // an enclosed air pocket in the tissue
  at({0.0, 0.0, 0.5}) = 40.0f;    // a marrow voxel in the bone
  at({2.4, 2.4, 2.4}) = 40.0f;    // a speck of "body" outside (table, noise)
  at({1.6, 0.0, 0.6}) = 1000.0f;  // a bone speck in the tissue
  LabelImage labels;
  LabellingSummary summary;
  const Status s = LabelTissue(ct, SmallScene(), labels, summary);
  ASSERT_TRUE(s.ok) << s.message;
  auto label = [&](const Eigen::Vector3d& x) {
    const Eigen::Vector3d s = g.toScaled(x);
    return labels.labels[g.index(int(std::lround(s[0] / 0.1)), int(std::lround(s[1] / 0.1)),
                                 int(std::lround(s[2] / 0.1)))];
  };
  EXPECT_EQ(label({1.5, 0.0, 0.0}), kSoftTissue);
  EXPECT_EQ(label({0.0, 0.0, 0.5}), kBone);
  EXPECT_EQ(label({2.4, 2.4, 2.4}), kAir);
  EXPECT_EQ(label({1.6, 0.0, 0.6}), kSoftTissue);
  EXPECT_EQ(summary.cavityVoxelsFilled, 1);
  EXPECT_EQ(summary.boneHoleVoxelsFilled, 1);

  LabellingOptions keepAll = SmallScene();
  keepAll.keepLargestComponent = false;
  keepAll.fillBoneHoles = false;
  keepAll.minimumBoneComponentVolume = 0.0;
  ASSERT_TRUE(LabelTissue(ct, keepAll, labels, summary).ok);
  EXPECT_EQ(label({2.4, 2.4, 2.4}), kSoftTissue);
  EXPECT_EQ(label({0.0, 0.0, 0.5}), kSoftTissue);
  EXPECT_EQ(label({1.6, 0.0, 0.6}), kBone);
}

TEST(TissueLabelling, SeparateMandibleSplitsTwoPiecesJoinedByAThinBridge) {
  // Two bone balls joined by a one-voxel bridge inside one tissue block: the opening cuts the
  // bridge, the smaller ball becomes the mandible.
  CTImage ct;
  ct.grid.dims = {60, 30, 30};
  ct.grid.spacing = {1.0, 1.0, 1.0};
  ct.hounsfield.assign(ct.grid.numVoxels(), -1000.0f);
  for (int k = 2; k < 28; ++k)
    for (int j = 2; j < 28; ++j)
      for (int i = 2; i < 58; ++i) {
        const Eigen::Vector3d x(i, j, k);
        float hu = 40.0f;
        if ((x - Eigen::Vector3d(18, 15, 15)).norm() < 9.0 ||
            (x - Eigen::Vector3d(42, 15, 15)).norm() < 6.0 ||
            (j == 15 && k == 15 && i > 20 && i < 40))
          hu = 1000.0f;
        ct.hounsfield[ct.grid.index(i, j, k)] = hu;
      }
  LabellingOptions options;
  options.separateMandible = true;
  LabelImage labels;
  LabellingSummary summary;
  ASSERT_TRUE(LabelTissue(ct, options, labels, summary).ok);
  EXPECT_TRUE(summary.mandibleSeparated);
  EXPECT_EQ(labels.labels[ct.grid.index(42, 15, 15)], kMandible);
  EXPECT_EQ(labels.labels[ct.grid.index(18, 15, 15)], kBone);
  EXPECT_NEAR(double(summary.mandibleVoxels), 4.0 / 3.0 * M_PI * 216.0,
              0.15 * 4.0 / 3.0 * M_PI * 216.0);

  // One solid piece stays one label.
  for (int i = 20; i < 40; ++i)
    for (int j = 10; j < 20; ++j)
      for (int k = 10; k < 20; ++k)
        ct.hounsfield[ct.grid.index(i, j, k)] = 1000.0f;
  ASSERT_TRUE(LabelTissue(ct, options, labels, summary).ok);
  EXPECT_FALSE(summary.mandibleSeparated);
  EXPECT_EQ(summary.mandibleVoxels, 0);
}

TEST(TissueLabelling, BadInputsGiveNamedErrors) {
  LabelImage labels;
  LabellingSummary summary;
  CTImage ct = ShellCT();
  LabellingOptions o = SmallScene();
  o.boneThreshold = 2000.0;
  Status s = LabelTissue(ct, o, labels, summary);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(Contains(s.message, "no voxel at or above BoneThreshold")) << s.message;

  o = SmallScene();
  o.skinThreshold = 500.0;
  o.boneThreshold = 100.0;
  s = LabelTissue(ct, o, labels, summary);
  EXPECT_TRUE(Contains(s.message, "thresholds in the wrong order")) << s.message;

  CTImage allBone = ct;
  for (float& v : allBone.hounsfield)
    v = v > 0.0f ? 1000.0f : v;
  s = LabelTissue(allBone, SmallScene(), labels, summary);
  EXPECT_TRUE(Contains(s.message, "soft-tissue label is empty")) << s.message;

  ct.hounsfield.pop_back();
  EXPECT_FALSE(LabelTissue(ct, SmallScene(), labels, summary).ok);
}

TEST(TissueModelParameters, InvalidParametersAreNamed) {
  TissueModelParameters p;
  EXPECT_TRUE(ValidateParameters(p).ok);
  p.meshing.cellSize = 0.0;
  EXPECT_TRUE(Contains(ValidateParameters(p).message, "CellSize must be positive"));
  p.meshing.cellSize = -1.0;
  EXPECT_TRUE(Contains(ValidateParameters(p).message, "CellSize must be positive"));
  p = TissueModelParameters();
  p.meshing.surfaceDistance = 0.0;
  EXPECT_TRUE(Contains(ValidateParameters(p).message, "SurfaceDistance"));
  p = TissueModelParameters();
  p.labelling.skinThreshold = 300.0;
  EXPECT_TRUE(Contains(ValidateParameters(p).message, "thresholds in the wrong order"));
}

TEST(TissueModelParameters, OverBudgetRunsAreRefusedBeforeMeshing) {
  TissueModelParameters p;
  p.labelling = SmallScene();
  p.meshing.cellSize = 0.05;
  p.maximumCells = 100000;
  bool meshed = false;
  LabelMesher mesher = [&](const LabelImage&, const MeshingParameters&, LabeledTetMesh&,
                           std::atomic<bool>*, const MeshingProgress&) {
    meshed = true;
    return Status::Error("must not be called");
  };
  TissueModel model;
  const Status s = BuildTissueModel(ShellCT(), p, mesher, model);
  ASSERT_FALSE(s.ok);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(Contains(s.message, "exceeds MaximumCells")) << s.message;
  EXPECT_FALSE(meshed);
  // The estimate: the shell's volume over a regular tetrahedron's, plus the boundary facets: the
  // staircase of a voxelised sphere has 1.5 times its area (the mean of |nx| + |ny| + |nz|).
  const double h = 0.05, tet = h * h * h / (6.0 * std::sqrt(2.0));
  const double facet = std::sqrt(3.0) / 4.0 * h * h;
  EXPECT_NEAR(model.estimatedCells,
              kCellsPerVolumeCell *
                      (4.0 / 3.0 * M_PI * 7.0 / tet + 4.0 / 3.0 * M_PI / (8.0 * tet)) +
                  kCellsPerBoundaryFacet * 1.5 * 4.0 * M_PI * (1.0 + 4.0) / facet,
              0.05 * model.estimatedCells);
}

TEST(TetQuality, RegularAndDegenerateTetrahedra) {
  // A regular tetrahedron (alternate cube corners), and one whose apex sits at its centroid.
  TetMesh mesh;
  mesh.points.resize(5, 3);
  mesh.points << 1, 1, 1, -1, 1, -1, 1, -1, -1, -1, -1, 1, 0, 0, 0;
  mesh.tets.resize(2, 4);
  mesh.tets << 0, 1, 2, 3, 0, 1, 2, 4;
  Eigen::Matrix<double, 4, 3> c;
  for (int k = 0; k < 4; ++k)
    c.row(k) = mesh.points.row(k);
  const double regular = std::acos(1.0 / 3.0) * 180.0 / M_PI;
  EXPECT_NEAR(TetMinDihedralAngle(c), regular, 1e-9);
  TetQualitySummary q = MeasureTetQuality(mesh, 10.0);
  EXPECT_EQ(q.cells, 2);
  EXPECT_EQ(q.nonPositive, 0);
  EXPECT_EQ(q.belowDihedralBound, 0);
  EXPECT_NEAR(q.smallestMeanRatio, TetMeanRatio([&] {
                Eigen::Matrix<double, 4, 3> d;
                for (int k = 0; k < 4; ++k)
                  d.row(k) = mesh.points.row(mesh.tets(1, k));
                return d;
              }()),
              1e-12);
  mesh.tets.row(1) << 0, 2, 1, 4; // inverted
  EXPECT_EQ(MeasureTetQuality(mesh, 10.0).nonPositive, 1);
  // Apex close to the face (0 1 2): a flat cell with a small dihedral angle.
  mesh.points.row(4) = 0.97 * (mesh.points.row(0) + mesh.points.row(1) + mesh.points.row(2)) / 3.0;
  mesh.tets.row(1) << 0, 1, 2, 4;
  q = MeasureTetQuality(mesh, 10.0);
  EXPECT_LT(q.worstDihedralAngle, 10.0);
  EXPECT_EQ(q.belowDihedralBound, 1);
  EXPECT_EQ(q.nonPositive, 0);
}

TEST(TissueModelExtraction, ShellLayersSplitIntoTissueBoneAndSkin) {
  // A generated shell whose inner layer is labelled bone: the tissue is the outer layers, the bone
  // surface the interface sphere, the skin the outer sphere, with consistent normals.
  const ShellMesh shell = MakeSphericalShell(4, 3, 1.0, 2.0);
  LabeledTetMesh labelled;
  labelled.mesh = shell.mesh;
  labelled.tetLabel.resize(std::size_t(shell.mesh.numTets()));
  int boneCells = 0;
  for (Eigen::Index e = 0; e < shell.mesh.numTets(); ++e) {
    double r = 0.0;
    for (int k = 0; k < 4; ++k)
      r += shell.mesh.points.row(shell.mesh.tets(e, k)).norm() / 4.0;
    const bool bone = r < 1.0 + 1.0 / 3.0;
    labelled.tetLabel[std::size_t(e)] = bone ? kBone : kSoftTissue;
    boneCells += bone;
  }
  TissueModel model;
  ASSERT_TRUE(ExtractTissueModel(labelled, model).ok);
  EXPECT_EQ(model.tissue.numTets(), shell.mesh.numTets() - boneCells);
  EXPECT_EQ(model.boneFacets.rows(),
            model.skinFacets.rows()); // both spheres carry the same triangulation
  const double interface = 1.0 + 1.0 / 3.0;
  auto check = [&](const Facets& f, double radius, double sign) {
    double flux = 0.0;
    for (Eigen::Index t = 0; t < f.rows(); ++t) {
      const Eigen::Vector3d a = model.tissue.points.row(f(t, 0)),
                            b = model.tissue.points.row(f(t, 1)),
                            c = model.tissue.points.row(f(t, 2));
      for (const Eigen::Vector3d& p : {a, b, c})
        EXPECT_NEAR(p.norm(), radius, 1e-9);
      flux += (b - a).cross(c - a).dot((a + b + c) / 3.0);
    }
    EXPECT_GT(sign * flux, 0.0); // normals point away from the centre (sign +1) or towards it
  };
  check(model.skinFacets, 2.0, +1.0);       // out of the tissue
  check(model.boneFacets, interface, +1.0); // out of the bone, into the tissue
  for (int l : model.boneLabel)
    EXPECT_EQ(l, kBone);
}
