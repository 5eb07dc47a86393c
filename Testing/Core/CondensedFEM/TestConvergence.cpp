// SPDX-License-Identifier: BSD-3-Clause
// Thick hollow sphere, radial displacement prescribed on the inner surface, free outer surface:
// u(r) = A r + B / r^2 with sigma_rr(b) = 0 (Core/AnalyticHollowSphere.h). Linear tetrahedra
// converge at order 2 in L2.
#include "CondensedFEM/CondensedFEM.h"
#include "Element/ElementStiffness.h"
#include "Support/AnalyticHollowSphere.h"
#include "Support/ShellMeshGenerator.h"

#include <cmath>
#include <gtest/gtest.h>

using namespace faceplan;

namespace {

// The relative L2 error of the solve on the given shell and its mesh size h. A failed precompute
// or solve stops the test (ASSERT) instead of reading a null system.
void SolveAndMeasure(int subdivisions, int layers, double& h, double& relativeError) {
  HollowSphere exact;
  const ShellMesh shell = MakeSphericalShell(subdivisions, layers, exact.a, exact.b);
  PrecomputeRequest request;
  request.mesh = shell.mesh;
  request.materials = Materials::Uniform(exact.E, exact.nu);
  request.sets.constrained = shell.innerNodes;
  request.sets.movable = shell.innerNodes;
  request.sets.kept = shell.outerNodes;
  request.options.method = SolveMethod::CachedFactor; // one solve: no dense response needed
  std::shared_ptr<const CondensedSystem> system;
  const Status pre = Precompute(request, system);
  ASSERT_TRUE(pre.ok && system) << pre.message;
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(shell.innerNodes.size()), 3);
  for (size_t k = 0; k < shell.innerNodes.size(); ++k)
    input.movableDisplacement.row(k) =
        exact.displacement(shell.mesh.points.row(shell.innerNodes[k]).transpose()).transpose();
  input.recoverInterior = true;
  SolveResult result;
  const Status solved = Solve(*system, input, result);
  ASSERT_TRUE(solved.ok) << solved.message;
  h = (exact.b - exact.a) / layers;
  double l2Exact;
  relativeError = HollowSphereL2Error(shell.mesh, result.allDisplacement, exact, l2Exact) / l2Exact;
}

} // namespace

TEST(Convergence, HollowSphereL2OrderAtLeast1p8) {
  std::vector<double> errors, sizes;
  for (int level : {1, 2, 4, 8}) {
    double h = 0.0, error = 0.0;
    SolveAndMeasure(3 * level, level, h, error);
    if (::testing::Test::HasFatalFailure())
      return;
    errors.push_back(error);
    sizes.push_back(h);
  }
  for (size_t k = 1; k < errors.size(); ++k) {
    const double order = std::log(errors[k - 1] / errors[k]) / std::log(sizes[k - 1] / sizes[k]);
    std::printf("h = %.4f  relative L2 error = %.3e  observed order = %.3f\n", sizes[k], errors[k],
                order);
    if (k >= 2)
      EXPECT_GE(order, 1.8) << "between refinements " << k - 1 << " and " << k;
  }
  EXPECT_LT(errors.back(), errors.front());
}
