// Thick hollow sphere, radial displacement prescribed on the inner surface, free outer surface:
// u(r) = A r + B / r^2 with sigma_rr(b) = 0. Linear tetrahedra converge at order 2 in L2.
#include "CondensedFEM.h"
#include "ElementStiffness.h"
#include "ShellMeshGenerator.h"

#include <cmath>
#include <gtest/gtest.h>

using namespace faceplan;

namespace {

struct HollowSphere {
  double a = 1.0, b = 2.0, ua = 0.01, E = 1.0, nu = 0.3;
  double A = 0, B = 0;
  HollowSphere() {
    double lambda, mu;
    LameParameters(E, nu, lambda, mu);
    // sigma_rr(b) = (3 lambda + 2 mu) A - 4 mu B / b^3 = 0 and A a + B / a^2 = ua.
    const double ratio = 4.0 * mu / ((3.0 * lambda + 2.0 * mu) * b * b * b); // A = ratio * B
    B = ua / (ratio * a + 1.0 / (a * a));
    A = ratio * B;
  }
  Eigen::Vector3d displacement(const Eigen::Vector3d& x) const {
    const double r = x.norm();
    return (A * r + B / (r * r)) * x / r;
  }
};

// L2 norm of the error over the mesh with the degree-2 four-point rule per tetrahedron.
double L2Error(const TetMesh& mesh, const Displacements& u, const HollowSphere& exact, double& l2Exact) {
  const double alpha = 0.5854101966249685, beta = 0.1381966011250105;
  double err2 = 0.0, ref2 = 0.0;
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k) c.row(k) = mesh.points.row(mesh.tets(e, k));
    const double w = TetVolume(c) / 4.0;
    for (int q = 0; q < 4; ++q) {
      Eigen::Vector4d bary = Eigen::Vector4d::Constant(beta);
      bary[q] = alpha;
      Eigen::Vector3d x = Eigen::Vector3d::Zero(), uh = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        x += bary[k] * c.row(k).transpose();
        uh += bary[k] * u.row(mesh.tets(e, k)).transpose();
      }
      const Eigen::Vector3d ue = exact.displacement(x);
      err2 += w * (uh - ue).squaredNorm();
      ref2 += w * ue.squaredNorm();
    }
  }
  l2Exact = std::sqrt(ref2);
  return std::sqrt(err2);
}

double SolveAndMeasure(int subdivisions, int layers, double& h) {
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
  EXPECT_TRUE(Precompute(request, system).ok);
  SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(shell.innerNodes.size()), 3);
  for (size_t k = 0; k < shell.innerNodes.size(); ++k)
    input.movableDisplacement.row(k) = exact.displacement(shell.mesh.points.row(shell.innerNodes[k]).transpose()).transpose();
  input.recoverInterior = true;
  SolveResult result;
  EXPECT_TRUE(Solve(*system, input, result).ok);
  h = (exact.b - exact.a) / layers;
  double l2Exact;
  return L2Error(shell.mesh, result.allDisplacement, exact, l2Exact) / l2Exact;
}

} // namespace

TEST(Convergence, HollowSphereL2OrderAtLeast1p8) {
  std::vector<double> errors, sizes;
  for (int level : {1, 2, 4, 8}) {
    double h;
    errors.push_back(SolveAndMeasure(3 * level, level, h));
    sizes.push_back(h);
  }
  for (size_t k = 1; k < errors.size(); ++k) {
    const double order = std::log(errors[k - 1] / errors[k]) / std::log(sizes[k - 1] / sizes[k]);
    std::printf("h = %.4f  relative L2 error = %.3e  observed order = %.3f\n", sizes[k], errors[k], order);
    if (k >= 2) EXPECT_GE(order, 1.8) << "between refinements " << k - 1 << " and " << k;
  }
  EXPECT_LT(errors.back(), errors.front());
}
