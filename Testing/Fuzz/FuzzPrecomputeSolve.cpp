// SPDX-License-Identifier: BSD-3-Clause
// Precompute and Solve on small random meshes: a block of 1 or 2 cubes (six tetrahedra
// each) whose nodes move at random, with random node classes, materials, methods, element orders
// and loads. Promises checked: no crash; a success is finite; the solve agrees with an independent
// one (the uncondensed reference for linear cells, the other condensed method for quadratic ones)
// when the system is reasonably conditioned.
#include "FuzzBytes.h"
#include "FuzzPrecompute.h"

#include "CondensedFEM/CondensedFEM.h"
#include "Mesh/TetGeometry.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

using namespace faceplan;
using faceplan::fuzz::CheckedPrecompute;
using faceplan::fuzz::FuzzBytes;
using faceplan::fuzz::Violation;

namespace {

// Kuhn split of each unit cube of an nx x ny x nz block into six positively oriented tetrahedra.
TetMesh CubeBlock(int nx, int ny, int nz) {
  TetMesh mesh;
  auto id = [=](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  mesh.points.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        mesh.points.row(id(i, j, k)) << i, j, k;
  static const int paths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::vector<Eigen::Vector4i> tets;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& path : paths) {
          int c[3] = {i, j, k};
          Eigen::Vector4i t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[path[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          tets.push_back(t);
        }
  mesh.tets.resize(Eigen::Index(tets.size()), 4);
  for (std::size_t e = 0; e < tets.size(); ++e) {
    Eigen::Vector4i t = tets[e];
    TetCorners corners;
    for (int k = 0; k < 4; ++k)
      corners.row(k) = mesh.points.row(t[k]);
    if (TetVolume(corners) < 0)
      std::swap(t[2], t[3]);
    mesh.tets.row(Eigen::Index(e)) = t.transpose();
  }
  return mesh;
}

double Magnitude(FuzzBytes& in, int lowExponent, int highExponent) {
  return std::pow(10.0, in.range(lowExponent, highExponent)) * (1.0 + 0.5 * in.scaled(1.0));
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzBytes in(data, size);
  PrecomputeRequest request;
  // One cube (6 tetrahedra) three times in four, else two: small systems keep an execution cheap.
  request.mesh = in.byte() % 4 == 0 ? CubeBlock(2, 1, 1) : CubeBlock(1, 1, 1);
  const int n = int(request.mesh.numPoints()), m = int(request.mesh.numTets());
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      request.mesh.points(i, c) += in.scaled(0.45);
  // Node classes: bit 0 constrained, bit 1 movable (when constrained), bit 2 kept.
  for (int i = 0; i < n; ++i) {
    const std::uint8_t classes = in.byte();
    if (classes & 1)
      request.sets.constrained.push_back(i);
    if ((classes & 3) == 3)
      request.sets.movable.push_back(i);
    if (classes & 4)
      request.sets.kept.push_back(i);
  }
  const bool perCell = in.flag();
  const Eigen::Index materialCount = perCell ? m : 1;
  request.materials.youngsModulus.resize(materialCount);
  request.materials.poissonRatio.resize(materialCount);
  request.materials.density.resize(materialCount);
  for (Eigen::Index e = 0; e < materialCount; ++e) {
    request.materials.youngsModulus[e] = Magnitude(in, -3, 9);
    // Ordinary ratios, and ratios approaching the incompressible limit.
    request.materials.poissonRatio[e] =
        in.flag() ? 0.49 * in.scaled(1.0) : 0.5 - std::pow(10.0, -in.range(1, 8));
    request.materials.density[e] = Magnitude(in, -9, 3);
  }
  PrecomputeOptions& options = request.options;
  options.method = static_cast<SolveMethod>(in.range(0, 2));
  // Linear half the time (quadratic cells cost a second precompute for the reference).
  options.elementOrder = static_cast<ElementOrder>(std::max(0, in.range(-1, 2)));
  options.responseBlockColumns = in.range(1, 8);
  options.quadraticMeanDilatation = in.flag();

  std::shared_ptr<const CondensedSystem> system;
  if (!CheckedPrecompute(request, system))
    return 0;
  SolveInput input;
  input.movableDisplacement.resize(Eigen::Index(request.sets.movable.size()), 3);
  for (Eigen::Index i = 0; i < input.movableDisplacement.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      input.movableDisplacement(i, c) = in.scaled(0.2);
  if (in.flag())
    input.gravity << in.scaled(10.0), in.scaled(10.0), in.scaled(10.0); // sequenced reads
  if (in.flag()) {
    input.nodalLoads = RowVectors3d::Zero(n, 3);
    for (int i = 0; i < n; ++i)
      if (in.flag())
        input.nodalLoads.row(i) << in.scaled(1.0), in.scaled(1.0), in.scaled(1.0);
  }
  input.recoverInterior = in.flag();
  SolveResult result;
  const Status solved = Solve(*system, input, result);
  if (!solved) {
    if (solved.message.empty())
      Violation("a Solve error without a message");
    return 0;
  }
  if (!result.keptDisplacement.allFinite() || !result.allDisplacement.allFinite())
    Violation("Solve succeeded with a non-finite displacement");
  if (result.keptDisplacement.rows() != Eigen::Index(request.sets.kept.size()))
    Violation("kept displacement has the wrong number of rows");

  // The reference: the uncondensed solve for linear cells (it knows no others), else a fresh
  // precompute with the other condensed method.
  SolveResult reference;
  const SystemInfo info = Describe(*system);
  if (options.elementOrder == ElementOrder::Linear) {
    if (!SolveFullReference(request, input, reference))
      return 0;
  } else {
    PrecomputeRequest other = request;
    other.options.method = info.method == SolveMethod::CachedFactor ? SolveMethod::DenseResponse
                                                                    : SolveMethod::CachedFactor;
    std::shared_ptr<const CondensedSystem> otherSystem;
    if (!Precompute(other, otherSystem) || !Solve(*otherSystem, input, reference))
      return 0;
  }
  const double scale =
      reference.keptDisplacement.size() ? reference.keptDisplacement.cwiseAbs().maxCoeff() : 0.0;
  const double difference =
      result.keptDisplacement.size()
          ? (result.keptDisplacement - reference.keptDisplacement).cwiseAbs().maxCoeff()
          : 0.0;
  // Both are direct solves of the same system: they may differ by the conditioning times
  // round-off, nothing more.
  if (info.conditionEstimate < 1e5 && difference > 1e-6 * scale + 1e-300) {
    std::fprintf(stderr, "method %s, order %s, condition %.3g, difference %.3g of %.3g\n",
                 MethodName(info.method), ElementOrderName(info.elementOrder),
                 info.conditionEstimate, difference, scale);
    Violation("the condensed solve disagrees with the reference solve");
  }
  return 0;
}
