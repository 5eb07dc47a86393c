// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/TraditionalBandSolve.h"

#include "Common/BlasThreads.h"
#include "Common/ExceptionBoundary.h"
#include "Comparison/ReverseCuthillMcKee.h"
#include "Element/ElementStiffness.h"
#include "Mesh/InputValidation.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <dlfcn.h>
#include <sstream>

namespace faceplan {

namespace {

// Fortran LAPACK with the trailing hidden length of the character argument.
using Pbtrf = void (*)(const char*, const int*, const int*, double*, const int*, int*, std::size_t);
using Pbtrs = void (*)(const char*, const int*, const int*, const int*, const double*, const int*,
                       double*, const int*, int*, std::size_t);

struct Lapack {
  Pbtrf pbtrf = nullptr;
  Pbtrs pbtrs = nullptr;
  std::string why;
};

const Lapack& FindLapack() {
  static const Lapack lapack = [] {
    Lapack l;
    void* self = RTLD_DEFAULT;
    l.pbtrf = reinterpret_cast<Pbtrf>(dlsym(self, "dpbtrf_"));
    l.pbtrs = reinterpret_cast<Pbtrs>(dlsym(self, "dpbtrs_"));
    for (const char* name : {"liblapack.so.3", "libopenblas.so.0", "liblapack.so"}) {
      if (l.pbtrf && l.pbtrs)
        break;
      void* handle = dlopen(name, RTLD_NOW | RTLD_GLOBAL);
      if (!handle)
        continue;
      l.pbtrf = reinterpret_cast<Pbtrf>(dlsym(handle, "dpbtrf_"));
      l.pbtrs = reinterpret_cast<Pbtrs>(dlsym(handle, "dpbtrs_"));
    }
    if (!l.pbtrf || !l.pbtrs)
      l.why = "LAPACK's dpbtrf_/dpbtrs_ were not found (no liblapack.so.3 loaded)";
    return l;
  }();
  return lapack;
}

Status TraditionalImpl(const PrecomputeRequest& request, const RowVectors3d& movable,
                       TraditionalBandResult& r, const TraditionalBandOptions& options) {
  r = TraditionalBandResult();
  const Lapack& lapack = FindLapack();
  if (!lapack.pbtrf)
    return Status::Error(lapack.why);
  const TetMesh& mesh = request.mesh;
  const NodeSets& sets = request.sets;
  Status status = ValidateSolveInputs(mesh, request.materials, sets);
  if (!status)
    return status;
  if (movable.rows() != static_cast<Eigen::Index>(sets.movable.size()))
    return Status::Error("expected one ROI displacement per movable node");
  if (!movable.allFinite())
    return Status::Error("prescribed displacements contain NaN or infinite values");

  StageClock clock;
  const Eigen::Index n = mesh.numPoints(), m = mesh.numTets();

  // Reordering: free nodes (used, not constrained), their graph, reverse Cuthill-McKee.
  std::vector<char> used(n, 0), constrained(n, 0);
  for (Eigen::Index e = 0; e < m; ++e)
    for (int k = 0; k < 4; ++k)
      used[mesh.tets(e, k)] = 1;
  for (int i : sets.constrained)
    constrained[i] = 1;
  std::vector<int> naturalIndex(n, -1), freeNode;
  for (Eigen::Index i = 0; i < n; ++i)
    if (used[i] && !constrained[i]) {
      naturalIndex[i] = static_cast<int>(freeNode.size());
      freeNode.push_back(static_cast<int>(i));
    }
  const int numFree = static_cast<int>(freeNode.size());
  std::vector<std::vector<int>> neighbours(numFree);
  for (Eigen::Index e = 0; e < m; ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const int ia = naturalIndex[mesh.tets(e, a)], ib = naturalIndex[mesh.tets(e, b)];
        if (a != b && ia >= 0 && ib >= 0)
          neighbours[ia].push_back(ib);
      }
  std::vector<int> start(numFree + 1, 0), adjacent;
  for (int v = 0; v < numFree; ++v) {
    auto& list = neighbours[v];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    start[v + 1] = start[v] + static_cast<int>(list.size());
  }
  adjacent.reserve(start[numFree]);
  for (auto& list : neighbours)
    adjacent.insert(adjacent.end(), list.begin(), list.end());
  neighbours.clear();
  std::vector<int> natural(numFree);
  for (int v = 0; v < numFree; ++v)
    natural[v] = v;
  r.semiBandwidthBefore = 3 * GraphBandwidth(start, adjacent, natural) + 2;
  const std::vector<int> order = ReverseCuthillMcKee(start, adjacent);
  std::vector<int> freeIndex(n, -1);
  for (int k = 0; k < numFree; ++k)
    freeIndex[freeNode[order[k]]] = k;
  const int nodeBand = GraphBandwidth(start, adjacent, order);
  const int kd = numFree > 0 ? 3 * nodeBand + 2 : 0;
  const int dofs = 3 * numFree;
  r.freeDofs = dofs;
  r.semiBandwidth = kd;
  r.bandBytes = 8.0 * double(kd + 1) * double(dofs);
  r.reorderingMs = clock.lapMs();
  const double flops = double(dofs) * double(kd) * double(kd);
  if (r.bandBytes > options.maxBandBytes || flops > options.maxFactorFlops) {
    std::ostringstream why;
    why.precision(3);
    why << "band matrix too large for this run: " << dofs << " DOFs, semi-bandwidth " << kd << ", "
        << r.bandBytes / 1e9 << " GB, about " << flops / 1e9 << " GFLOP to factor";
    return Status::Error(why.str());
  }

  // Element stiffness, one thread.
  std::vector<ElementMatrix> ke(static_cast<size_t>(m));
  TetCorners corners;
  for (Eigen::Index e = 0; e < m; ++e) {
    for (int k = 0; k < 4; ++k)
      corners.row(k) = mesh.points.row(mesh.tets(e, k));
    ke[e] = TetStiffness(corners, request.materials.E(e), request.materials.nu(e));
  }
  r.elementStiffnessMs = clock.lapMs();

  // Assembly into LAPACK 'U' band storage: A(i, j), i <= j, at ab[kd + i - j + j * (kd + 1)].
  const int ldab = kd + 1;
  std::vector<double> ab(static_cast<size_t>(ldab) * dofs, 0.0);
  int dofOf[12];
  for (Eigen::Index e = 0; e < m; ++e) {
    bool any = false;
    for (int k = 0; k < 4; ++k) {
      const int f = freeIndex[mesh.tets(e, k)];
      any |= f >= 0;
      for (int c = 0; c < 3; ++c)
        dofOf[3 * k + c] = f >= 0 ? 3 * f + c : -1;
    }
    if (!any)
      continue;
    const ElementMatrix& K = ke[e];
    for (int p = 0; p < 12; ++p) {
      const int i = dofOf[p];
      if (i < 0)
        continue;
      for (int q = 0; q < 12; ++q) {
        const int j = dofOf[q];
        if (j < i)
          continue; // upper triangle only (j >= i); skips -1 too
        ab[static_cast<size_t>(kd + i - j) + static_cast<size_t>(j) * ldab] += K(p, q);
      }
    }
  }
  r.assemblyMs = clock.lapMs();

  // Boundary condition: prescribed values moved to the right-hand side, element by element.
  RowVectors3d prescribed = RowVectors3d::Zero(n, 3);
  for (size_t k = 0; k < sets.movable.size(); ++k)
    prescribed.row(sets.movable[k]) = movable.row(k);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(dofs);
  for (Eigen::Index e = 0; e < m; ++e) {
    bool anyFree = false, anyPrescribed = false;
    Eigen::Matrix<double, 12, 1> ue = Eigen::Matrix<double, 12, 1>::Zero();
    for (int k = 0; k < 4; ++k) {
      const int node = mesh.tets(e, k);
      anyFree |= freeIndex[node] >= 0;
      if (constrained[node]) {
        ue.segment<3>(3 * k) = prescribed.row(node).transpose();
        anyPrescribed |= prescribed.row(node).squaredNorm() > 0.0;
      }
    }
    if (!anyFree || !anyPrescribed)
      continue;
    const Eigen::Matrix<double, 12, 1> fe = ke[e] * ue;
    for (int k = 0; k < 4; ++k) {
      const int f = freeIndex[mesh.tets(e, k)];
      if (f >= 0)
        rhs.segment<3>(3 * f) -= fe.segment<3>(3 * k);
    }
  }
  ke.clear();
  ke.shrink_to_fit();
  r.boundaryConditionMs = clock.lapMs();

  Eigen::VectorXd x = rhs;
  if (dofs > 0) {
    ScopedBlasThreads oneThread(1);
    // Keep the assembled band for the residual check (outside the timed stages).
    std::vector<double> original = ab;
    clock.lapMs();
    int info = 0;
    lapack.pbtrf("U", &dofs, &kd, ab.data(), &ldab, &info, 1);
    r.factorizationMs = clock.lapMs();
    if (info != 0)
      return Status::Error("band Cholesky failed (dpbtrf info " + std::to_string(info) +
                           "): the free stiffness is not positive definite");
    const int one = 1;
    lapack.pbtrs("U", &dofs, &kd, &one, ab.data(), &ldab, x.data(), &dofs, &info, 1);
    r.solveMs = clock.lapMs();
    if (info != 0)
      return Status::Error("dpbtrs failed, info " + std::to_string(info));
    // Residual with the stored band (symmetric product), untimed.
    Eigen::VectorXd y = Eigen::VectorXd::Zero(dofs);
    for (int j = 0; j < dofs; ++j)
      for (int i = std::max(0, j - kd); i <= j; ++i) {
        const double a = original[static_cast<size_t>(kd + i - j) + static_cast<size_t>(j) * ldab];
        y[i] += a * x[j];
        if (i != j)
          y[j] += a * x[i];
      }
    const double bn = rhs.norm();
    r.relativeResidual = bn > 0 ? (y - rhs).norm() / bn : x.norm();
  }
  // Total of the timed stages (the residual check's copy of the band is not part of the route).
  r.totalMs = r.reorderingMs + r.elementStiffnessMs + r.assemblyMs + r.boundaryConditionMs +
              r.factorizationMs + r.solveMs;

  RowVectors3d all = prescribed;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (freeIndex[i] >= 0)
      all.row(i) = x.segment<3>(3 * freeIndex[i]).transpose();
    else if (!constrained[i])
      all.row(i).setZero();
  }
  r.keptDisplacement.resize(static_cast<Eigen::Index>(sets.kept.size()), 3);
  for (size_t k = 0; k < sets.kept.size(); ++k)
    r.keptDisplacement.row(k) = all.row(sets.kept[k]);
  if (options.recoverAll)
    r.allDisplacement = all;
  if (!all.allFinite())
    return Status::Error("the band solve produced non-finite values");
  return Status::Ok();
}

} // namespace

bool BandLapackAvailable(std::string* why) {
  const Lapack& l = FindLapack();
  if (why)
    *why = l.why;
  return l.pbtrf && l.pbtrs;
}

Status SolveTraditionalBand(const PrecomputeRequest& request, const RowVectors3d& movable,
                            TraditionalBandResult& result, const TraditionalBandOptions& options) {
  return ReturnStatusOnException("the band solve", [&]() -> Status {
    return TraditionalImpl(request, movable, result, options);
  });
}

} // namespace faceplan
