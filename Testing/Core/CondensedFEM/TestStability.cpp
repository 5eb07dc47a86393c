// SPDX-License-Identifier: BSD-3-Clause
// Numerical stability on stiff and extreme cases: near-incompressible tissue and locking,
// stiffness contrast and unit rescaling, degenerate and sliver elements, under-constrained pieces,
// large displacements, single-precision per-edit products.
#include "Common/RelativeDifference.h"
#include "Comparison/FloatCpuBackend.h"
#include "Element/ElementStiffness.h"
#include "Mesh/MeshValidation.h"
#include "Support/FEMTestScenes.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

// Thick hollow sphere a = 1, b = 2, radial displacement ua on the inner surface, free outer
// surface: u(r) = A r + B / r^2 with sigma_rr(b) = 0.
struct HollowSphere {
  double a = 1.0, b = 2.0, ua = 0.01, E = 1.0, nu;
  double A = 0, B = 0;
  explicit HollowSphere(double poisson) : nu(poisson) {
    double lambda, mu;
    LameParameters(E, nu, lambda, mu);
    const double ratio = 4.0 * mu / ((3.0 * lambda + 2.0 * mu) * b * b * b);
    B = ua / (ratio * a + 1.0 / (a * a));
    A = ratio * B;
  }
  Eigen::RowVector3d displacement(const Eigen::RowVector3d& x) const {
    const double r = x.norm();
    return (A * r + B / (r * r)) * x / r;
  }
};

struct SphereRun {
  double nodalError = 0.0; // RMS over corner nodes of |u_h - u| / RMS |u|
  double residual = 0.0, condition = 0.0;
  long long dofs = 0;
  double precomputeMs = 0.0;
  double factorNonzeros = 0.0;
  bool ok = false;
};

// ~35k linear tetrahedra: 60 * 12^2 * 4 = 34560.
constexpr int kSub = 12, kLayers = 4;

SphereRun SolveSphere(const ShellMesh& shell, double nu, ElementOrder order,
                      SolveMethod method = SolveMethod::CachedFactor) {
  const HollowSphere exact(nu);
  PrecomputeRequest request;
  request.mesh = shell.mesh;
  request.materials = Materials::Uniform(exact.E, nu);
  request.sets.constrained = shell.innerNodes;
  request.sets.movable = shell.innerNodes;
  request.sets.kept = shell.outerNodes;
  request.options.method = method;
  request.options.elementOrder = order;
  // Mid-edge nodes of boundary edges on the sphere they belong to.
  request.options.midEdgeProjection = [&exact](const Eigen::Vector3d& mid, int,
                                               int) -> Eigen::Vector3d {
    const double r = mid.norm();
    return mid * ((r < 0.5 * (exact.a + exact.b) ? exact.a : exact.b) / r);
  };
  SphereRun run;
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  EXPECT_TRUE(s.ok) << s.message;
  if (!s)
    return run;
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(shell.innerNodes.size()), 3);
  for (size_t k = 0; k < shell.innerNodes.size(); ++k)
    input.movableDisplacement.row(k) =
        exact.displacement(shell.mesh.points.row(shell.innerNodes[k]));
  input.recoverInterior = true;
  SolveResult result;
  s = Solve(*system, input, result);
  EXPECT_TRUE(s.ok) << s.message;
  if (!s)
    return run;
  double err2 = 0.0, ref2 = 0.0;
  for (Eigen::Index i = 0; i < shell.mesh.numPoints(); ++i) {
    const Eigen::RowVector3d ue = exact.displacement(shell.mesh.points.row(i));
    err2 += (result.allDisplacement.row(i) - ue).squaredNorm();
    ref2 += ue.squaredNorm();
  }
  const SystemInfo info = Describe(*system);
  run.nodalError = std::sqrt(err2 / ref2);
  run.residual = result.relativeResidual;
  run.condition = result.conditionEstimate;
  run.dofs = info.freeDofs + info.roiDofs;
  run.precomputeMs = info.precomputeTimings[Stage::Total].ms;
  run.factorNonzeros = info.factorNonzeros;
  run.ok = result.allDisplacement.allFinite();
  EXPECT_EQ(result.elementOrder, order);
  return run;
}

const ShellMesh& SphereMesh() {
  static const ShellMesh shell = MakeSphericalShell(kSub, kLayers, 1.0, 2.0);
  return shell;
}

// Linear errors by nu, shared by the tests below (computed once).
const std::vector<SphereRun>& LinearRuns() {
  static const std::vector<SphereRun> runs = [] {
    std::vector<SphereRun> out;
    for (double nu : {0.45, 0.49, 0.499, 0.4999})
      out.push_back(SolveSphere(SphereMesh(), nu, ElementOrder::Linear));
    return out;
  }();
  return runs;
}
const double kNus[4] = {0.45, 0.49, 0.499, 0.4999};

} // namespace

// ---- 1. near-incompressible ------------------------------------------------------------------

TEST(Stability, NearIncompressibleLinearIsFiniteWithResidualAndCondition) {
  ASSERT_EQ(SphereMesh().mesh.numTets(), 34560);
  const auto& runs = LinearRuns();
  for (int k = 0; k < 4; ++k) {
    std::printf("STABILITY linear  nu=%-7g tets=%lld dofs=%lld error=%.3f%% residual=%.2e "
                "cond=%.2e precompute=%.0f ms\n",
                kNus[k], (long long)SphereMesh().mesh.numTets(), runs[k].dofs,
                100 * runs[k].nodalError, runs[k].residual, runs[k].condition,
                runs[k].precomputeMs);
    EXPECT_TRUE(runs[k].ok);
    EXPECT_LE(runs[k].residual, 1e-9) << "nu " << kNus[k];
    EXPECT_TRUE(std::isfinite(runs[k].condition) && runs[k].condition > 1.0) << runs[k].condition;
  }
  // The condition estimate grows as the material becomes incompressible, and linear cells lock.
  EXPECT_GT(runs[3].condition, runs[0].condition);
  EXPECT_GT(runs[3].nodalError, 3.0 * runs[0].nodalError);
}

// Quadratic cells with mean dilatation (P2-P0) on the same ~35k-cell mesh: the error no longer
// grows with lambda. Measured (docs/STABILITY.md): 0.085% at nu = 0.45, 0.36% at 0.499, 0.47% at
// 0.4999, against 2.7%, 34% and 76% for linear cells. The locking bound (error at 0.499 within 1.5x
// the error at 0.45) is NOT met: P2-P0's constant pressure limits its incompressible accuracy to
// O(h^2) while the compressible P2 error is O(h^3), so the ratio is ~4.2x (see the docs);
// QuadraticNodalPressure meets it (QuadraticNodalPressureMeetsLockingBound).
TEST(Stability, QuadraticElementsDoNotLock) {
  const auto& linear = LinearRuns();
  const SphereRun q45 = SolveSphere(SphereMesh(), 0.45, ElementOrder::Quadratic);
  const SphereRun q499 = SolveSphere(SphereMesh(), 0.499, ElementOrder::Quadratic);
  const SphereRun* q[2] = {&q45, &q499};
  const double nus[2] = {0.45, 0.499};
  for (int k = 0; k < 2; ++k) {
    std::printf("STABILITY quadratic nu=%-7g tets=%lld dofs=%lld error=%.3f%% residual=%.2e "
                "cond=%.2e precompute=%.0f ms\n",
                nus[k], (long long)SphereMesh().mesh.numTets(), q[k]->dofs, 100 * q[k]->nodalError,
                q[k]->residual, q[k]->condition, q[k]->precomputeMs);
    EXPECT_TRUE(q[k]->ok);
    EXPECT_LE(q[k]->residual, 1e-9);
  }
  std::printf("STABILITY quadratic error ratio 0.499 / 0.45 = %.2f (target 1.5)\n",
              q499.nodalError / q45.nodalError);
  EXPECT_LT(q45.nodalError, 0.1 * linear[0].nodalError);
  EXPECT_LT(q499.nodalError, 0.2 * linear[0].nodalError); // better than linear cells at nu = 0.45
  EXPECT_LT(q499.nodalError, 0.02 * linear[2].nodalError);
}

// Robustness in lambda: from nu = 0.499 to 0.4999 (lambda x10) the quadratic error barely moves
// while the linear error doubles (a smaller mesh keeps this fast).
TEST(Stability, QuadraticErrorIndependentOfLambda) {
  const ShellMesh shell = MakeSphericalShell(6, 2, 1.0, 2.0);
  const SphereRun l499 = SolveSphere(shell, 0.499, ElementOrder::Linear);
  const SphereRun l4999 = SolveSphere(shell, 0.4999, ElementOrder::Linear);
  const SphereRun q499 = SolveSphere(shell, 0.499, ElementOrder::Quadratic);
  const SphereRun q4999 = SolveSphere(shell, 0.4999, ElementOrder::Quadratic);
  std::printf("STABILITY small mesh (%lld tets): linear %.3f%% -> %.3f%%, quadratic %.3f%% -> "
              "%.3f%% (nu 0.499 -> 0.4999)\n",
              (long long)shell.mesh.numTets(), 100 * l499.nodalError, 100 * l4999.nodalError,
              100 * q499.nodalError, 100 * q4999.nodalError);
  EXPECT_LE(q4999.nodalError, 1.5 * q499.nodalError);
  EXPECT_GT(l499.nodalError, 10.0 * q499.nodalError);
  EXPECT_LE(q4999.residual, 1e-9);
}

// Quadratic cells with a continuous nodal pressure (P2-P1, lumped pressure mass) meet the locking
// bound: the error at nu = 0.499 (and 0.4999) within 1.5x the error at 0.45 on the same mesh.
// Measured (docs/STABILITY.md): 4,320 cells 0.318% / 0.347% / 0.347% (x1.09); 34,560 cells
// 0.095% / 0.098% / 0.098% (x1.03). This check uses the 4,320-cell shell (a few seconds); the
// 34,560-cell check below takes minutes (its factor is ~6x Quadratic's), so it is
// disabled by default: run it with --gtest_also_run_disabled_tests.
TEST(Stability, QuadraticNodalPressureMeetsLockingBound) {
  const ShellMesh shell = MakeSphericalShell(6, 2, 1.0, 2.0);
  const SphereRun n45 = SolveSphere(shell, 0.45, ElementOrder::QuadraticNodalPressure);
  const SphereRun n499 = SolveSphere(shell, 0.499, ElementOrder::QuadraticNodalPressure);
  const SphereRun n4999 = SolveSphere(shell, 0.4999, ElementOrder::QuadraticNodalPressure);
  const SphereRun q499 = SolveSphere(shell, 0.499, ElementOrder::Quadratic);
  std::printf("STABILITY nodal-pressure (%lld tets, dofs=%lld factor nnz=%.3g): %.3f%% / %.3f%% / "
              "%.3f%% at nu 0.45 / 0.499 / 0.4999 "
              "(ratio %.2f, %.2f; Quadratic at 0.499: %.3f%%, factor nnz %.3g)\n",
              (long long)shell.mesh.numTets(), n45.dofs, n45.factorNonzeros, 100 * n45.nodalError,
              100 * n499.nodalError, 100 * n4999.nodalError, n499.nodalError / n45.nodalError,
              n4999.nodalError / n45.nodalError, 100 * q499.nodalError, q499.factorNonzeros);
  for (const SphereRun* r : {&n45, &n499, &n4999}) {
    EXPECT_TRUE(r->ok);
    EXPECT_LE(r->residual, 1e-9);
  }
  EXPECT_LE(n499.nodalError, 1.5 * n45.nodalError);
  EXPECT_LE(n4999.nodalError, 1.5 * n45.nodalError);
  EXPECT_LT(n499.nodalError, 0.5 * q499.nodalError);
}

TEST(Stability, DISABLED_QuadraticNodalPressureMeetsLockingBoundOn35kCells) {
  ASSERT_EQ(SphereMesh().mesh.numTets(), 34560);
  const SphereRun n45 = SolveSphere(SphereMesh(), 0.45, ElementOrder::QuadraticNodalPressure);
  const SphereRun n499 = SolveSphere(SphereMesh(), 0.499, ElementOrder::QuadraticNodalPressure);
  for (const SphereRun* r : {&n45, &n499}) {
    std::printf("STABILITY nodal-pressure nu=%-7g tets=%lld dofs=%lld error=%.4f%% residual=%.2e "
                "cond=%.2e factor nnz=%.3g precompute=%.0f ms\n",
                r == &n45 ? 0.45 : 0.499, (long long)SphereMesh().mesh.numTets(), r->dofs,
                100 * r->nodalError, r->residual, r->condition, r->factorNonzeros, r->precomputeMs);
    EXPECT_TRUE(r->ok);
    EXPECT_LE(r->residual, 1e-9);
  }
  std::printf("STABILITY nodal-pressure error ratio 0.499 / 0.45 = %.2f (target 1.5)\n",
              n499.nodalError / n45.nodalError);
  EXPECT_LE(n499.nodalError, 1.5 * n45.nodalError);
}

// Quadratic cells reproduce a linear field exactly through condensation and the dense response,
// and agree with the cached-factor path; inputs and outputs stay in the linear mesh's numbering.
TEST(Stability, QuadraticWorksWithCondensationAndCaching) {
  // Every boundary node prescribed with a linear field; the middle layer kept (interior nodes).
  const ShellMesh shell = MakeSphericalShell(3, 2, 1.0, 2.0);
  PrecomputeRequest request;
  request.mesh = shell.mesh;
  request.materials = Materials::Uniform(3000.0, 0.499);
  request.sets.constrained = shell.innerNodes;
  request.sets.constrained.insert(request.sets.constrained.end(), shell.outerNodes.begin(),
                                  shell.outerNodes.end());
  request.sets.movable = request.sets.constrained;
  for (int i = shell.nodesPerLayer; i < 2 * shell.nodesPerLayer; ++i)
    request.sets.kept.push_back(i);
  const Eigen::Matrix3d G =
      (Eigen::Matrix3d() << 1e-3, 2e-3, 0, -1e-3, 5e-4, 1e-3, 0, 3e-4, -2e-3).finished();
  RowVectors3d linearField(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  for (size_t k = 0; k < request.sets.movable.size(); ++k)
    linearField.row(k) =
        (G * request.mesh.points.row(request.sets.movable[k]).transpose()).transpose();
  for (ElementOrder order : {ElementOrder::Quadratic, ElementOrder::QuadraticNodalPressure})
    for (SolveMethod method : {SolveMethod::DenseResponse, SolveMethod::CachedFactor}) {
      request.options.elementOrder = order;
      request.options.method = method;
      std::shared_ptr<const CondensedSystem> system;
      Status s = Precompute(request, system);
      ASSERT_TRUE(s.ok) << s.message;
      const SystemInfo info = Describe(*system);
      EXPECT_EQ(info.elementOrder, order);
      EXPECT_GT(info.solverNodes, request.mesh.numPoints());
      SolveInput input;
      input.movableDisplacement = linearField;
      for (bool interior : {false, true}) {
        input.recoverInterior = interior;
        SolveResult result;
        s = Solve(*system, input, result);
        ASSERT_TRUE(s.ok) << s.message;
        EXPECT_LE(result.relativeResidual, 1e-9);
        ASSERT_EQ(result.keptDisplacement.rows(),
                  static_cast<Eigen::Index>(request.sets.kept.size()));
        for (size_t k = 0; k < request.sets.kept.size(); ++k) {
          const Eigen::RowVector3d expected =
              (G * request.mesh.points.row(request.sets.kept[k]).transpose()).transpose();
          EXPECT_LT((result.keptDisplacement.row(k) - expected).norm(), 1e-9)
              << MethodName(method) << " " << ElementOrderName(order);
        }
        if (interior) {
          ASSERT_EQ(result.allDisplacement.rows(), request.mesh.numPoints());
          for (Eigen::Index i = 0; i < request.mesh.numPoints(); ++i) {
            const Eigen::RowVector3d expected =
                (G * request.mesh.points.row(i).transpose()).transpose();
            EXPECT_LT((result.allDisplacement.row(i) - expected).norm(), 1e-9);
          }
        }
      }
    }
}

TEST(Stability, QuadraticDenseAndCachedAgreeWithLoads) {
  for (ElementOrder order : {ElementOrder::Quadratic, ElementOrder::QuadraticNodalPressure}) {
    PrecomputeRequest request = ShellRequest(3, 2, 3000.0, 0.49);
    request.options.elementOrder = order;
    if (order == ElementOrder::QuadraticNodalPressure) { // per-cell materials, contrast 1e4
      request.materials.youngsModulus = Eigen::VectorXd::Constant(request.mesh.numTets(), 3000.0);
      for (Eigen::Index e = 0; e < request.mesh.numTets(); e += 5)
        request.materials.youngsModulus[e] = 3.0e7;
    }
    SolveInput input;
    input.movableDisplacement = SmoothRoiField(request);
    input.gravity = Eigen::Vector3d(0.0, -9810.0, 0.0);
    input.nodalLoads = RowVectors3d::Zero(request.mesh.numPoints(), 3);
    for (int id : request.sets.kept)
      input.nodalLoads.row(id) << 0.01, 0.02, -0.01;
    RowVectors3d kept[2];
    int k = 0;
    for (SolveMethod method : {SolveMethod::DenseResponse, SolveMethod::CachedFactor}) {
      request.options.method = method;
      std::shared_ptr<const CondensedSystem> system;
      Status s = Precompute(request, system);
      ASSERT_TRUE(s.ok) << s.message;
      SolveResult result;
      s = Solve(*system, input, result);
      ASSERT_TRUE(s.ok) << s.message;
      EXPECT_LE(result.relativeResidual, 1e-9);
      kept[k++] = result.keptDisplacement;
    }
    EXPECT_LT(RelativeMaxDifference(kept[0], kept[1]), 1e-9) << ElementOrderName(order);
  }
}

// ---- 2. stiffness contrast and units -----------------------------------------------------------

namespace {

// Bone (E * contrast) in the inner layer of cells, soft tissue elsewhere.
PrecomputeRequest ContrastRequest(double contrast, double lengthScale, double stressScale) {
  PrecomputeRequest request = ShellRequest(6, 4, 3000.0, 0.45);
  const ShellMesh shell = MakeSphericalShell(6, 4, 1.0, 2.0); // only for the layer size
  request.materials.youngsModulus = Eigen::VectorXd::Constant(request.mesh.numTets(), 3000.0);
  for (Eigen::Index e = 0; e < request.mesh.numTets(); ++e) {
    bool inner = false;
    for (int k = 0; k < 4; ++k)
      inner |= request.mesh.tets(e, k) < shell.nodesPerLayer;
    if (inner || e % 7 == 0)
      request.materials.youngsModulus[e] = 3000.0 * contrast;
  }
  request.mesh.points *= lengthScale;
  request.materials.youngsModulus *= stressScale;
  return request;
}

} // namespace

TEST(Stability, StiffnessContrastUpTo1e6MeetsResidual) {
  for (double contrast : {1e2, 1e4, 1e6}) {
    PrecomputeRequest request = ContrastRequest(contrast, 1.0, 1.0);
    SolveInput input;
    input.movableDisplacement = SmoothRoiField(request);
    for (SolveMethod method : {SolveMethod::DenseResponse, SolveMethod::CachedFactor}) {
      request.options.method = method;
      std::shared_ptr<const CondensedSystem> system;
      Status s = Precompute(request, system);
      ASSERT_TRUE(s.ok) << s.message;
      for (bool interior : {false, true}) {
        input.recoverInterior = interior;
        SolveResult result;
        s = Solve(*system, input, result);
        ASSERT_TRUE(s.ok) << s.message;
        std::printf(
            "STABILITY contrast=%g method=%s interior=%d residual=%.2e cond=%.2e refinement=%d\n",
            contrast, MethodName(method), interior, result.relativeResidual,
            result.conditionEstimate, result.refinementSteps);
        EXPECT_LE(result.relativeResidual, 1e-9);
        EXPECT_TRUE(result.keptDisplacement.allFinite());
      }
    }
    SolveResult reference;
    input.recoverInterior = false;
    ASSERT_TRUE(SolveFullReference(request, input, reference).ok);
    EXPECT_LE(reference.relativeResidual, 1e-9);
  }
}

TEST(Stability, UnitRescalingChangesResultBy1e8AtMost) {
  const double contrast = 1e6;
  PrecomputeRequest mmPa = ContrastRequest(contrast, 1.0, 1.0);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(mmPa);
  input.recoverInterior = true;
  double worst = 0.0;
  RowVectors3d base;
  // (length scale, stress scale): mm -> m and Pa -> MPa, separately and together.
  const double scales[4][2] = {{1.0, 1.0}, {1e-3, 1.0}, {1.0, 1e-6}, {1e-3, 1e-6}};
  for (const auto& sc : scales) {
    PrecomputeRequest request = ContrastRequest(contrast, sc[0], sc[1]);
    request.options.method = SolveMethod::DenseResponse;
    SolveInput scaled = input;
    scaled.movableDisplacement *= sc[0];
    std::shared_ptr<const CondensedSystem> system;
    ASSERT_TRUE(Precompute(request, system).ok);
    SolveResult result;
    ASSERT_TRUE(Solve(*system, scaled, result).ok);
    EXPECT_LE(result.relativeResidual, 1e-9);
    const RowVectors3d inMm = result.allDisplacement / sc[0];
    if (base.size() == 0)
      base = inMm;
    else
      worst = std::max(worst, RelativeMaxDifference(inMm, base));
  }
  std::printf("STABILITY unit rescaling (contrast 1e6): largest relative change %.2e\n", worst);
  EXPECT_LE(worst, 1e-8);
}

// ---- 3. degenerate elements and slivers ------------------------------------------------------

TEST(Stability, DegenerateCellsListFirstIdsAndCount) {
  PrecomputeRequest r = ShellRequest(3, 2);
  for (int e = 10; e < 40; e += 2)
    std::swap(r.mesh.tets(e, 0), r.mesh.tets(e, 1)); // 15 inverted
  r.mesh.tets(5, 3) = r.mesh.tets(5, 0);             // 1 flat
  std::shared_ptr<const CondensedSystem> system;
  const Status s = Precompute(r, system);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("zero-volume cells 5;"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("inverted cells 10, 12, 14"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("(15 in all)"), std::string::npos) << s.message;
}

// Two cells on one face: with the second cell's apex below the face the mesh is valid; above it,
// both cells keep a positive volume but overlap, and the precompute names the fold.
TEST(Stability, FoldedCellsWarnAndValidNeighboursDoNot) {
  for (bool folded : {false, true}) {
    PrecomputeRequest request;
    request.mesh.points.resize(5, 3);
    request.mesh.points << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.3, 0.3, folded ? 0.5 : -0.5;
    request.mesh.tets.resize(2, 4);
    request.mesh.tets << 0, 1, 2, 3, 0, 1, 2, 4;
    if (!folded)
      request.mesh.tets.row(1) << 0, 2, 1, 4; // positive volume with the apex below
    request.materials = Materials::Uniform(3000.0, 0.45);
    request.sets.constrained = {0, 1, 2};
    request.sets.kept = {3, 4};
    FoldReport report;
    const std::string w = CheckFoldedFaces(request.mesh, SharedFaces(request.mesh), &report);
    EXPECT_EQ(report.foldedFaces, folded ? 1 : 0);
    std::shared_ptr<const CondensedSystem> system;
    Status s = Precompute(request, system);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(Describe(*system).foldedFaces, folded ? 1 : 0);
    bool named = false;
    for (const std::string& warning : s.warnings)
      named = named || warning.find("1 pairs of tetrahedra that share a face") != std::string::npos;
    EXPECT_EQ(named, folded) << w;
  }
}

TEST(Stability, SliversWarnWithCountAndWorstQualityAndStillSolve) {
  // Squash the first layer of a shell to 1/1000 of its thickness: its cells become slivers.
  const int sub = 4, layers = 3;
  PrecomputeRequest request = ShellRequest(sub, layers, 3000.0, 0.45);
  const ShellMesh shell = MakeSphericalShell(sub, layers, 1.0, 2.0);
  QualityReport before;
  EXPECT_TRUE(CheckElementQuality(request.mesh, 0.02, &before).empty())
      << "the generator's cells are all above the default threshold (worst " << before.worstQuality
      << ")";
  const double inner = request.mesh.points.row(0).norm();
  const double thickness = request.mesh.points.row(shell.nodesPerLayer).norm() - inner;
  for (int i = shell.nodesPerLayer; i < 2 * shell.nodesPerLayer; ++i)
    request.mesh.points.row(i) *= (inner + 1e-3 * thickness) / request.mesh.points.row(i).norm();
  std::shared_ptr<const CondensedSystem> system;
  Status s = Precompute(request, system);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_FALSE(s.warnings.empty());
  const long long expected = 60LL * sub * sub; // the squashed layer
  const SystemInfo info = Describe(*system);
  std::printf("STABILITY slivers: %lld cells below 0.02, worst mean ratio %.2e; warning: %s\n",
              info.sliverCells, info.worstQuality, s.warnings[0].c_str());
  EXPECT_GE(info.sliverCells, expected);
  EXPECT_LT(info.worstQuality, 0.02);
  EXPECT_NE(s.warnings[0].find(std::to_string(info.sliverCells) + " sliver tetrahedra"),
            std::string::npos);
  EXPECT_NE(s.warnings[0].find("worst"), std::string::npos);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request, 0.01);
  input.recoverInterior = true;
  SolveResult result;
  s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_LE(result.relativeResidual, 1e-9);
  EXPECT_TRUE(result.allDisplacement.allFinite());
}

// ---- 4. under-constrained --------------------------------------------------------------------

namespace {

// Appends a copy of `piece` shifted by `offset`; returns the id offset of its nodes.
int AppendPiece(TetMesh& mesh, const TetMesh& piece, const Eigen::RowVector3d& offset,
                int shareNodes = 0) {
  const int n = static_cast<int>(mesh.numPoints()), m = static_cast<int>(mesh.numTets());
  mesh.points.conservativeResize(n + piece.numPoints(), 3);
  for (Eigen::Index i = 0; i < piece.numPoints(); ++i)
    mesh.points.row(n + i) = piece.points.row(i) + offset;
  mesh.tets.conservativeResize(m + piece.numTets(), 4);
  mesh.tets.bottomRows(piece.numTets()) = piece.tets.array() + n;
  (void)shareNodes;
  return n;
}

std::string PrecomputeMessage(const PrecomputeRequest& request) {
  std::shared_ptr<const CondensedSystem> system;
  const Status s = Precompute(request, system);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(system, nullptr);
  return s.message;
}

} // namespace

TEST(Stability, TwoPieceMeshNamesTheFreePiece) {
  PrecomputeRequest request = ShellRequest(3, 1);
  const TetMesh piece = MakeSphericalShell(2, 1, 1.0, 2.0).mesh;
  AppendPiece(request.mesh, piece, Eigen::RowVector3d(100.0, 0.0, 0.0));
  const std::string msg = PrecomputeMessage(request);
  EXPECT_NE(msg.find("attached to no constrained node"), std::string::npos) << msg;
  EXPECT_NE(msg.find(std::to_string(piece.numTets()) + " cells"), std::string::npos) << msg;
  EXPECT_NE(msg.find("[98, 102]"), std::string::npos) << msg;
}

TEST(Stability, PieceHangingOnOneNodeOrEdgeIsAnErrorNotASingularMatrix) {
  for (int shared : {1, 2}) {
    PrecomputeRequest request = ShellRequest(3, 1);
    // A single tetrahedron that shares only a node or an edge with the tissue's outer surface: the
    // tissue holds it, but it can rotate about that node or edge.
    const int n = static_cast<int>(request.mesh.numPoints()),
              m = static_cast<int>(request.mesh.numTets());
    const int a = request.sets.kept[0];
    // An outer neighbour of a along the surface: any node of a cell containing a, also kept.
    int b = -1;
    std::vector<char> isKept(n, 0);
    for (int id : request.sets.kept)
      isKept[id] = 1;
    for (Eigen::Index e = 0; e < m && b < 0; ++e)
      for (int k = 0; k < 4; ++k)
        if (request.mesh.tets(e, k) == a)
          for (int j = 0; j < 4; ++j)
            if (request.mesh.tets(e, j) != a && isKept[request.mesh.tets(e, j)])
              b = request.mesh.tets(e, j);
    ASSERT_GE(b, 0);
    const Eigen::RowVector3d pa = request.mesh.points.row(a), pb = request.mesh.points.row(b);
    const Eigen::RowVector3d out = pa.normalized() * 0.5,
                             side = (pb - pa).cross(pa).normalized() * 0.3;
    request.mesh.points.conservativeResize(n + 3, 3);
    request.mesh.points.row(n) = pa + out + side;
    request.mesh.points.row(n + 1) = pa + out - side;
    request.mesh.points.row(n + 2) = pb + out;
    request.mesh.tets.conservativeResize(m + 1, 4);
    // shared == 1: hangs on node a; shared == 2: hangs on edge (a, b).
    if (shared == 1)
      request.mesh.tets.row(m) << a, n + 2, n, n + 1;
    else
      request.mesh.tets.row(m) << a, b, n, n + 1;
    TetCorners c;
    for (int k = 0; k < 4; ++k)
      c.row(k) = request.mesh.points.row(request.mesh.tets(m, k));
    if (TetVolume(c) < 0)
      std::swap(request.mesh.tets(m, 2), request.mesh.tets(m, 3));
    const std::string msg = PrecomputeMessage(request);
    EXPECT_NE(msg.find("can move rigidly"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1 cells"), std::string::npos) << msg;
  }
}

// ---- 5. large displacements ------------------------------------------------------------------

TEST(Stability, LargeStrainAndInvertedCellsAreReported) {
  // One layer: every cell has all corners kept or constrained, so kept-only solves check them too
  // (a kept-only solve can only check such cells).
  PrecomputeRequest request = ShellRequest(4, 1);
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  SolveInput input;
  // Small: no warning.
  input.movableDisplacement = SmoothRoiField(request, 0.01);
  input.recoverInterior = true;
  SolveResult result;
  Status s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings[0];
  EXPECT_LT(result.largestStrain, 0.1);
  // Large: the ROI pushed through the tissue.
  for (bool interior : {true, false}) {
    input.movableDisplacement = SmoothRoiField(request, 40.0);
    input.recoverInterior = interior;
    s = Solve(*system, input, result);
    ASSERT_TRUE(s.ok) << s.message;
    std::printf(
        "STABILITY large displacement (interior %d): strain %.1f%%, %lld inverted; %zu warnings\n",
        interior, 100 * result.largestStrain, result.invertedCells, s.warnings.size());
    for (const auto& w : s.warnings)
      std::printf("  warning: %s\n", w.c_str());
    EXPECT_GT(result.largestStrain, 0.1);
    ASSERT_FALSE(s.warnings.empty());
    EXPECT_NE(s.warnings[0].find("small-strain range of linear FEM"), std::string::npos);
    EXPECT_EQ(result.warnings, s.warnings);
    if (interior) {
      EXPECT_GT(result.invertedCells, 0);
      bool listed = false;
      for (const auto& w : s.warnings)
        listed |= w.find("inverted in the deformed result (cells ") != std::string::npos;
      EXPECT_TRUE(listed);
    }
  }
}

TEST(Stability, CheckDeformationOnAKnownField) {
  const ShellMesh shell = MakeSphericalShell(2, 1, 1.0, 2.0);
  // Uniform stretch of 20% in x: strain 0.2 everywhere, nothing inverted.
  RowVectors3d u(shell.mesh.numPoints(), 3);
  for (Eigen::Index i = 0; i < u.rows(); ++i)
    u.row(i) << 0.2 * shell.mesh.points(i, 0), 0, 0;
  std::vector<std::string> warnings;
  DeformationReport r = CheckDeformation(shell.mesh, u, warnings, 0.1);
  EXPECT_NEAR(r.largestStrain, 0.2, 1e-12);
  EXPECT_TRUE(r.invertedCells.empty());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("20%"), std::string::npos) << warnings[0];
  // A mirror in x (u = -2x): every cell inverted.
  for (Eigen::Index i = 0; i < u.rows(); ++i)
    u.row(i) << -2.0 * shell.mesh.points(i, 0), 0, 0;
  warnings.clear();
  r = CheckDeformation(shell.mesh, u, warnings, 0.1);
  EXPECT_EQ(static_cast<Eigen::Index>(r.invertedCells.size()), shell.mesh.numTets());
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[1].find(std::to_string(shell.mesh.numTets()) + " tetrahedra are inverted"),
            std::string::npos);
  EXPECT_NE(warnings[1].find("cells 0, 1, 2"), std::string::npos) << warnings[1];
}

// ---- 6. single precision ---------------------------------------------------------------------

TEST(Stability, SinglePrecisionResponseIsRedoneInDouble) {
  PrecomputeRequest request = ContrastRequest(1e4, 1.0, 1.0);
  request.options.method = SolveMethod::DenseResponse;
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  std::shared_ptr<const CondensedSystem> exactSystem, floatSystem, looseSystem;
  ASSERT_TRUE(Precompute(request, exactSystem).ok);
  SolveResult exact;
  ASSERT_TRUE(Solve(*exactSystem, input, exact).ok);
  EXPECT_FALSE(exact.redoneInDouble);
  EXPECT_TRUE(exact.precisionNote.empty());

  // Default tolerance: the float operator misses it, edits are redone in double.
  request.options.backend = MakeFloatCpuBackend();
  Status s = Precompute(request, floatSystem);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_NE(s.warnings.back().find("redone in double"), std::string::npos) << s.warnings.back();
  const SystemInfo info = Describe(*floatSystem);
  EXPECT_TRUE(info.responseRedoneInDouble);
  EXPECT_GT(info.responseProbeError, 1e-9);
  EXPECT_LT(info.responseProbeError, 1e-4);
  SolveResult redone;
  ASSERT_TRUE(Solve(*floatSystem, input, redone).ok);
  EXPECT_TRUE(redone.redoneInDouble);
  EXPECT_NE(redone.precisionNote.find("redone in double"), std::string::npos);
  EXPECT_LE(redone.relativeResidual, 1e-9);
  EXPECT_LT(RelativeMaxDifference(redone.keptDisplacement, exact.keptDisplacement), 1e-12);
  std::printf("STABILITY single precision: probe deviation %.2e -> %s\n", info.responseProbeError,
              redone.precisionNote.c_str());

  // A caller who accepts single precision keeps the float product, and the note says how good it
  // is.
  request.options.responseTolerance = 1e-4;
  ASSERT_TRUE(Precompute(request, looseSystem).ok);
  SolveResult loose;
  ASSERT_TRUE(Solve(*looseSystem, input, loose).ok);
  EXPECT_FALSE(loose.redoneInDouble);
  EXPECT_NE(loose.precisionNote.find("within the tolerance"), std::string::npos);
  const double floatError = RelativeMaxDifference(loose.keptDisplacement, exact.keptDisplacement);
  EXPECT_GT(floatError, 1e-12);
  EXPECT_LT(floatError, 1e-4);
}

TEST(Stability, IterativeRefinementReportsItsSteps) {
  // A tolerance below what one Cholesky solve reaches forces refinement; the result improves.
  PrecomputeRequest request = ContrastRequest(1e6, 1.0, 1.0);
  request.options.method = SolveMethod::CachedFactor;
  request.options.residualTolerance = 1e-30; // never met: uses every step
  request.options.maxRefinementSteps = 2;
  std::shared_ptr<const CondensedSystem> system;
  ASSERT_TRUE(Precompute(request, system).ok);
  SolveInput input;
  input.movableDisplacement = SmoothRoiField(request);
  SolveResult result;
  Status s = Solve(*system, input, result);
  ASSERT_TRUE(s.ok);
  EXPECT_EQ(result.refinementSteps, 2);
  EXPECT_LE(result.relativeResidual, 1e-12);
}
