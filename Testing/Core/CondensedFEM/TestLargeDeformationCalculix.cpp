// The large-deformation solve against CalculiX (*HYPERELASTIC, NEO HOOKE with NLGEOM, the same
// strain energy) on moves of tens of percent strain: a face-like shell whose ROI is pushed in, and
// a shell sliding on a curved surface (*TRANSFORM + the normal DOF) with its cap pushed out.
//
// Tolerance: job.dat prints 7 significant digits (e13.6), each component within 5e-7 of its size,
// so a node within sqrt(3) * 5e-7 < 9e-7 of the largest displacement. Both solvers stop at a
// residual of 1e-9 of their force scale (ours: LargeDeformationOptions::tolerance; ccx: R_alpha_n
// and R_alpha_p, the largest residual over the average force), and ccx's last Newton correction
// is about 1e-7 of the increment, so the converged states are known far more closely than the
// printed digits: tightening both tolerances a hundredfold leaves the differences unchanged. 2e-6
// is the printed digits' floor with a margin, and 5000 times below the difference to the linear
// model, which each scene asserts.
#include "CalculixRunner.h"
#include "Common/RelativeDifference.h"
#include "CondensedFEM/LargeDeformation.h"
#include "Support/FEMTestScenes.h"

#include <cstdlib>
#include <filesystem>
#include <gtest/gtest.h>
#include <string>

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

  std::shared_ptr<const CondensedSystem> system;
  s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  SolveResult linear;
  s = Solve(*system, input, linear);
  ASSERT_TRUE(s.ok) << s.message;

  const std::string dir =
      (std::filesystem::temp_directory_path() / ("faceplan_large_ccx_" + name)).string();
  std::filesystem::create_directories(dir);
  bench::CalculixOptions options;
  options.model = bench::CalculixModel::NeoHookean;
  const bench::CalculixResult ccx = bench::RunCalculix(request, moves, dir, options);
  ASSERT_TRUE(ccx.ok) << ccx.error;

  const double agreement = RelativeMaxNodeDifference(large.keptDisplacement, ccx.keptDisplacement);
  const double linearToCcx =
      RelativeMaxNodeDifference(linear.keptDisplacement, ccx.keptDisplacement);
  ::testing::Test::RecordProperty("agreement", std::to_string(agreement));
  ::testing::Test::RecordProperty("linear_to_ccx", std::to_string(linearToCcx));
  std::printf("%s: largest Green strain %.3f, load steps %d, |large - ccx| %.3g, |linear - ccx| "
              "%.3g (relative to max |u_ccx|)\n",
              name.c_str(), report.largestGreenStrain, report.loadSteps, agreement, linearToCcx);
  EXPECT_LT(agreement, kAgreement);
  EXPECT_GT(linearToCcx, kLinearDifference);
}

TEST(LargeDeformationCalculix, FaceLikeShellWithLargeRoiMoveAgrees) {
  if (!HaveCalculix())
    GTEST_SKIP() << "ccx (CalculiX) is not installed";
  const PrecomputeRequest request = ShellRequest(4, 2);
  ExpectAgreementWithCalculix(request, SmoothRoiField(request, 5.0), "shell", 0.2);
}

TEST(LargeDeformationCalculix, ShellSlidingOnACurvedSurfaceAgrees) {
  if (!HaveCalculix())
    GTEST_SKIP() << "ccx (CalculiX) is not installed";
  RowVectors3d moves;
  const PrecomputeRequest request = SlidingShellRequest(10.0, moves);
  ExpectAgreementWithCalculix(request, moves, "sliding", 0.2);
}

} // namespace
