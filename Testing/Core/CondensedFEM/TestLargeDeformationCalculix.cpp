// SPDX-License-Identifier: BSD-3-Clause
// The large-deformation solves (Newton's and the precomputed one) against CalculiX (*HYPERELASTIC,
// NEO HOOKE with NLGEOM, the same strain energy) on moves of tens of percent strain: a face-like
// shell whose ROI is pushed in, the same with per-cell materials, and a shell sliding on a curved
// surface (*TRANSFORM + the normal DOF) with its cap pushed out.
//
// Tolerance: job.dat prints 7 significant digits (e13.6), each component within 5e-7 of its size,
// so a node within sqrt(3) * 5e-7 < 9e-7 of the largest displacement. Both solvers stop at a
// residual of 1e-9 of their force scale (ours: LargeDeformationOptions::tolerance; ccx: R_alpha_n
// and R_alpha_p, the largest residual over the average force); ccx's last Newton corrections are
// below 1e-7 of the increment (job.cvg), and tightening the tolerances (ours to 1e-13, ccx's to
// 1e-11) leaves the differences unchanged, so what remains is the printed digits. 2e-6 is that
// floor with a margin; the linear model must differ by more than 5000 times as much.
#include "Common/RelativeDifference.h"
#include "CondensedFEM/LargeDeformation.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"
#include "Support/CalculixRunner.h"
#include "Support/FEMTestScenes.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <gtest/gtest.h>
#include <string>
#include <unistd.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

constexpr double kAgreement = 2e-6;
constexpr double kLinearDifference = 1e-2;

bool HaveCalculix() {
  return std::system("command -v ccx > /dev/null 2>&1") == 0;
}

// Solves the scene with SolveLargeDeformation, CalculiX's neo-Hookean NLGEOM step and the linear
// model, and checks that the first two agree and differ clearly from the third.
void ExpectAgreementWithCalculix(const PrecomputeRequest& request, const RowVectors3d& moves,
                                 const std::string& name, double minimumStrain) {
  SolveInput input;
  input.movableDisplacement = moves;
  SolveResult large;
  LargeDeformationReport report;
  Status s = SolveLargeDeformation(request, input, {}, large, report);
  ASSERT_TRUE(s.ok) << s.message;
  // The scene really is a large move, beyond the linear model's small-strain range.
  EXPECT_GT(report.largestGreenStrain, minimumStrain);
  // The precomputed solve (its factor, no factorization per update) reaches the same equilibrium.
  std::shared_ptr<LargeDeformationSystem> precomputed;
  s = PrecomputeLargeDeformation(request, {}, precomputed);
  ASSERT_TRUE(s.ok) << s.message;
  SolveResult fast;
  PrecomputedLargeDeformationReport fastReport;
  s = SolvePrecomputedLargeDeformation(*precomputed, input, nullptr, fast, fastReport);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_FALSE(fastReport.fellBack) << fastReport.fallbackReason;
  EXPECT_LT(RelativeMaxNodeDifference(fast.keptDisplacement, large.keptDisplacement), 1e-8);

  std::shared_ptr<const CondensedSystem> system;
  s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  SolveResult linear;
  s = Solve(*system, input, linear);
  ASSERT_TRUE(s.ok) << s.message;

  // One folder per process, so that runs in several build trees at once do not share job files.
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("faceplan_large_ccx_" + name + "_" + std::to_string(::getpid())))
                              .string();
  std::filesystem::create_directories(dir);
  bench::CalculixOptions options;
  options.model = bench::CalculixModel::NeoHookean;
  const bench::CalculixResult ccx = bench::RunCalculix(request, moves, dir, options);
  ASSERT_TRUE(ccx.ok) << ccx.error;

  const double agreement = RelativeMaxNodeDifference(large.keptDisplacement, ccx.keptDisplacement);
  const double fastAgreement =
      RelativeMaxNodeDifference(fast.keptDisplacement, ccx.keptDisplacement);
  ::testing::Test::RecordProperty("precomputed_agreement", std::to_string(fastAgreement));
  const double linearToCcx =
      RelativeMaxNodeDifference(linear.keptDisplacement, ccx.keptDisplacement);
  ::testing::Test::RecordProperty("agreement", std::to_string(agreement));
  ::testing::Test::RecordProperty("linear_to_ccx", std::to_string(linearToCcx));
  std::printf("%s: largest Green strain %.3f, load steps %d, |large - ccx| %.3g, |linear - ccx| "
              "%.3g (relative to max |u_ccx|)\n",
              name.c_str(), report.largestGreenStrain, report.loadSteps, agreement, linearToCcx);
  EXPECT_LT(agreement, kAgreement);
  EXPECT_LT(fastAgreement, kAgreement);
  EXPECT_GT(linearToCcx, kLinearDifference);
  if (!::testing::Test::HasFailure())
    std::filesystem::remove_all(dir); // kept for a look when the comparison fails
}

TEST(LargeDeformationCalculix, FaceLikeShellWithLargeRoiMoveAgrees) {
  if (!HaveCalculix())
    GTEST_SKIP() << "ccx (CalculiX) is not installed";
  const PrecomputeRequest request = ShellRequest(4, 2);
  ExpectAgreementWithCalculix(request, SmoothRoiField(request, 5.0), "shell", 0.2);
}

TEST(LargeDeformationCalculix, TwoLayerShellWithPerCellMaterialsAgrees) {
  // Per-cell (E, nu): a soft inner layer under a stiffer, less compressible outer one (ccx gets
  // one *MATERIAL per distinct pair).
  if (!HaveCalculix())
    GTEST_SKIP() << "ccx (CalculiX) is not installed";
  PrecomputeRequest request = ShellRequest(4, 2);
  const Eigen::Index cells = request.mesh.numTets();
  request.materials.youngsModulus.resize(cells);
  request.materials.poissonRatio.resize(cells);
  for (Eigen::Index e = 0; e < cells; ++e) {
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
    for (int a = 0; a < 4; ++a)
      centroid += 0.25 * request.mesh.points.row(request.mesh.tets(e, a));
    const bool inner = centroid.norm() < 87.5; // between the radii 80 and 95
    request.materials.youngsModulus[e] = inner ? 3000.0 : 9000.0;
    request.materials.poissonRatio[e] = inner ? 0.45 : 0.4;
  }
  ExpectAgreementWithCalculix(request, SmoothRoiField(request, 5.0), "layers", 0.2);
}

TEST(LargeDeformationCalculix, ShellSlidingOnACurvedSurfaceAgrees) {
  if (!HaveCalculix())
    GTEST_SKIP() << "ccx (CalculiX) is not installed";
  RowVectors3d moves;
  const PrecomputeRequest request = SlidingShellRequest(10.0, moves);
  ExpectAgreementWithCalculix(request, moves, "sliding", 0.2);
}

} // namespace
