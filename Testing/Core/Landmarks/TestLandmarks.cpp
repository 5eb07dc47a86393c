// SPDX-License-Identifier: BSD-3-Clause
// Landmark geometry on generated sections: a profile whose prominences, notches and concavities are
// known from its formula, the frames, the table's ratios and the published bands.
#include "Landmarks/ClinicalBands.h"
#include "Landmarks/FacialLandmarks.h"
#include "Landmarks/LandmarkTable.h"
#include "Osteotomy/OperationPresets.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using namespace faceplan;
using namespace faceplan::landmarks;

namespace {

// The polyline (x(s), y, s) for s in [s0, s1], as segment end points; anterior is -x.
Segments Polyline(const std::function<double(double)>& x, double s0, double s1, int n = 4000,
                  double y = 0.0) {
  Segments out;
  for (int k = 0; k < n; ++k) {
    const double a = s0 + (s1 - s0) * k / n, b = s0 + (s1 - s0) * (k + 1) / n;
    out.emplace_back(x(a), y, a);
    out.emplace_back(x(b), y, b);
  }
  return out;
}

double Bump(double s, double centre, double width, double height) {
  return height * std::exp(-0.5 * std::pow((s - centre) / width, 2));
}

// A face profile (mm): the nose at 140, upper lip at 104, lower lip at 88, chin at 64, with a
// fissure at 96; x grows backwards.
double FaceX(double s) {
  return 60.0 - Bump(s, 140, 5, 20) - Bump(s, 104, 5, 10) - Bump(s, 88, 4, 9) - Bump(s, 64, 6, 10) +
         Bump(s, 96, 0.8, 3);
}

Frame BadinFrame() {
  Frame f;
  EXPECT_TRUE(ModelAxesFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(),
                             -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), f));
  return f;
}

} // namespace

TEST(Landmarks, ProfileLandmarksByDefinition) {
  const Frame f = BadinFrame();
  Placement p;
  PlaceMidlineSkin(Polyline(FaceX, 40, 180), f, p);
  ASSERT_TRUE(p.has(Landmark::Pronasale));
  EXPECT_NEAR(p.at(Landmark::Pronasale).z(), 140.0, 0.2);
  EXPECT_NEAR(p.at(Landmark::LabraleSuperius).z(), 104.0, 0.5);
  EXPECT_NEAR(p.at(Landmark::LabraleInferius).z(), 88.0, 0.5);
  EXPECT_NEAR(p.at(Landmark::SoftTissuePogonion).z(), 64.0, 0.5);
  EXPECT_NEAR(p.at(Landmark::Stomion).z(), 96.0, 0.5);
  // Subnasale: between the nose and the upper lip, deepest behind their chord.
  const double sn = p.at(Landmark::Subnasale).z();
  EXPECT_GT(sn, 104.0);
  EXPECT_LT(sn, 140.0);
  const double b = p.at(Landmark::SoftTissueB).z();
  EXPECT_GT(b, 64.0);
  EXPECT_LT(b, 88.0);
  // Every point lies on the profile.
  for (Landmark l : {Landmark::Subnasale, Landmark::SoftTissueB})
    EXPECT_NEAR(p.at(l).x(), FaceX(p.at(l).z()), 1e-2);
}

TEST(Landmarks, TooFewProminencesSayWhy) {
  const Frame f = BadinFrame();
  Placement p;
  PlaceMidlineSkin(Polyline([](double s) { return 60.0 - Bump(s, 140, 5, 20); }, 40, 180), f, p);
  EXPECT_TRUE(p.has(Landmark::Pronasale));
  EXPECT_FALSE(p.has(Landmark::LabraleSuperius));
  EXPECT_NE(p.note[static_cast<int>(Landmark::Stomion)].find("prominences"), std::string::npos);
  Placement none;
  PlaceMidlineSkin(Segments{}, f, none);
  EXPECT_FALSE(none.has(Landmark::Pronasale));
  EXPECT_FALSE(none.note[static_cast<int>(Landmark::Pronasale)].empty());
}

TEST(Landmarks, BonyLandmarksFollowTheJaws) {
  const Frame f = BadinFrame();
  Placement p;
  PlaceMidlineSkin(Polyline(FaceX, 40, 180), f, p);
  // Maxilla: 99 to 126, receding upwards with a concavity near 115; mandible: 55 to 95, chin at 65.
  Segments bone =
      Polyline([](double s) { return 50.0 + 0.3 * (s - 99) + Bump(s, 115, 3, 2); }, 99, 126);
  const Segments mandible = Polyline(
      [](double s) { return 62.0 - Bump(s, 65, 4, 3) + Bump(s, 80, 4, 4) - 0.1 * (s - 80); }, 55,
      95);
  bone.insert(bone.end(), mandible.begin(), mandible.end());
  PlaceMidlineBone(bone, f, p);
  for (Landmark l :
       {Landmark::ANS, Landmark::APoint, Landmark::UpperIncisorTip, Landmark::LowerIncisorTip,
        Landmark::BPoint, Landmark::Pogonion, Landmark::Menton})
    ASSERT_TRUE(p.has(l)) << LandmarkName(l) << ": " << p.note[static_cast<int>(l)];
  EXPECT_NEAR(p.at(Landmark::UpperIncisorTip).z(), 99.0, 0.1);
  EXPECT_NEAR(p.at(Landmark::ANS).z(), 126.0, 0.1);
  EXPECT_NEAR(p.at(Landmark::APoint).z(), 115.0, 1.0);
  EXPECT_NEAR(p.at(Landmark::LowerIncisorTip).z(), 95.0, 0.1);
  EXPECT_NEAR(p.at(Landmark::Menton).z(), 55.0, 0.1);
  EXPECT_NEAR(p.at(Landmark::Pogonion).z(), 65.0, 1.0);
  EXPECT_NEAR(p.at(Landmark::BPoint).z(), 80.0, 1.5);
}

TEST(Landmarks, FramesAndTheirDegenerateCases) {
  Frame f;
  EXPECT_TRUE(ModelAxesFrame(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0, 2, 0),
                             Eigen::Vector3d(-1, 0.3, 0), Eigen::Vector3d(0.1, 0, 1), f));
  EXPECT_NEAR(f.anterior.dot(f.superior), 0.0, 1e-12);
  EXPECT_NEAR(f.anterior.dot(f.lateral), 0.0, 1e-12);
  EXPECT_NEAR(f.anterior.y(), 0.0, 1e-12); // projected into the midsagittal plane
  EXPECT_FALSE(ModelAxesFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                              -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), f));
  EXPECT_FALSE(ModelAxesFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(),
                              Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), f));
  EXPECT_FALSE(ModelAxesFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(),
                              -Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(), f));
  EXPECT_FALSE(ModelAxesFrame(Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d::UnitY(),
                              -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), f));
  // Frankfort: porions at x = 120, orbitale in front at x = 60, all at z = 150, tilted 10 degrees.
  const double t = 10.0 * M_PI / 180.0;
  auto tilt = [&](Eigen::Vector3d x) {
    return Eigen::Vector3d(x.x() * std::cos(t) - x.z() * std::sin(t), x.y(),
                           x.x() * std::sin(t) + x.z() * std::cos(t));
  };
  ASSERT_TRUE(FrankfortFrame(tilt({120, 60, 150}), tilt({120, -60, 150}), tilt({60, 0, 150}),
                             Eigen::Vector3d::UnitZ(), f));
  EXPECT_NEAR((f.anterior - tilt({-1, 0, 0})).norm(), 0.0, 1e-12);
  EXPECT_NEAR((f.superior - tilt({0, 0, 1})).norm(), 0.0, 1e-12);
  EXPECT_FALSE(
      FrankfortFrame({120, 60, 150}, {120, -60, 150}, {120, 0, 150}, Eigen::Vector3d::UnitZ(), f));
}

TEST(Landmarks, TableRatiosAndBands) {
  const Frame f = BadinFrame();
  Placement p;
  std::array<Eigen::Vector3d, kLandmarkCount> u;
  for (int i = 0; i < kLandmarkCount; ++i) {
    p.set(static_cast<Landmark>(i), Eigen::Vector3d(50, 0, 100 - i));
    u[i] = Eigen::Vector3d::Zero();
  }
  u[static_cast<int>(Landmark::Pogonion)] = {-6, 0, 0};             // 6 mm forward
  u[static_cast<int>(Landmark::SoftTissuePogonion)] = {-5.4, 0, 1}; // 0.9 of it
  u[static_cast<int>(Landmark::LowerIncisorTip)] = {-6, 0, 0};
  u[static_cast<int>(Landmark::LabraleInferius)] = {-5.7, 0, 0}; // 0.95: above 0.4-0.85
  std::vector<LandmarkRow> rows;
  ASSERT_TRUE(LandmarkRows(p, u, f, Operation::BSSO, 1e-3, rows));
  const LandmarkRow& pog = rows[static_cast<int>(Landmark::SoftTissuePogonion)];
  EXPECT_NEAR(pog.horizontal, 5.4, 1e-12);
  EXPECT_NEAR(pog.vertical, 1.0, 1e-12);
  EXPECT_NEAR(pog.ratio, 0.9, 1e-12);
  ASSERT_NE(pog.band, nullptr);
  EXPECT_EQ(pog.check, "in");
  EXPECT_EQ(rows[static_cast<int>(Landmark::LabraleInferius)].check, "out");
  EXPECT_EQ(rows[static_cast<int>(Landmark::Subnasale)].check, "paired bone does not move");
  // The same plan read as a genioplasty has no band for the lower lip.
  ASSERT_TRUE(LandmarkRows(p, u, f, Operation::Genioplasty, 1e-3, rows));
  EXPECT_EQ(rows[static_cast<int>(Landmark::LabraleInferius)].check, "no band");
  // A setback finds no advancement band.
  for (auto& d : u)
    d = -d;
  ASSERT_TRUE(LandmarkRows(p, u, f, Operation::BSSO, 1e-3, rows));
  EXPECT_EQ(rows[static_cast<int>(Landmark::SoftTissuePogonion)].check, "no band");
  u[0] = {NAN, 0, 0};
  EXPECT_FALSE(LandmarkRows(p, u, f, Operation::BSSO, 1e-3, rows));
}

TEST(Landmarks, EveryBandNamesItsSourceAndIsOrdered) {
  for (const ClinicalBand& b : ClinicalBands()) {
    EXPECT_FALSE(b.source.empty());
    EXPECT_LT(b.low, b.high);
    EXPECT_TRUE(IsSkinLandmark(b.landmark));
    EXPECT_EQ(FindBand(b.operation, b.movement, b.landmark), &b);
  }
  EXPECT_EQ(ClassifyMovement(5, 1), Movement::Advancement);
  EXPECT_EQ(ClassifyMovement(-5, 1), Movement::Setback);
  EXPECT_EQ(ClassifyMovement(1, 4), Movement::Impaction);
  EXPECT_EQ(ClassifyMovement(1, -4), Movement::Descent);
}
