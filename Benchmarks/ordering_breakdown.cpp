// SPDX-License-Identifier: BSD-3-Clause
// Where the ordering of K_FF spends its time (the ordering thread is the precompute's longest CPU
// path on the largest meshes): the calls StartEarlyOrdering makes, timed one by one on one
// thread, each the median of --repeats runs, on MakeFaceLikeScene(subdivisions, layers). Also the
// analysed factor's supernodal structure as the GPU response's backward sweep meets it: its flops
// (diagonal- block solves, off-diagonal products) and the least row traffic of its gathers.
//   ordering_breakdown [--subdivisions 50] [--layers 7] [--repeats 3]
// 50/7 is the GPU benchmark's 1M scene, 18/5 faceplan_benchmark's ~100k one.
#include "CondensedFEM/PrecomputeStages.h"
#include "SceneArguments.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/FillReducingOrdering.h"
#include "Support/FEMTestScenes.h"

#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <vector>

using namespace faceplan;

namespace {

double MedianMs(int repeats, const std::function<void()>& work) {
  std::vector<double> ms;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    work();
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

} // namespace

int main(int argc, char** argv) {
  benchmarks::SceneArguments args{50, 7, 3};
  if (!benchmarks::ParseSceneArguments(argc, argv, args))
    return 2;
  const int subdivisions = args.subdivisions, layers = args.layers, repeats = args.repeats;
  const PrecomputeRequest request = benchmarks::DenseResponseScene(args);
  PrecomputeState state(request, nullptr, ProgressCallback());
  // The validation starts the mesh checks on a thread: wait for them so nothing runs beside the
  // timed calls.
  if (Status s = ValidatePrecomputeRequest(state); !s)
    return std::fprintf(stderr, "%s\n", s.message.c_str()), 1;
  if (Status s = FinishMeshChecks(state); !s)
    return std::fprintf(stderr, "%s\n", s.message.c_str()), 1;
  if (Status s = SeparateNodes(state); !s)
    return std::fprintf(stderr, "%s\n", s.message.c_str()), 1;
  const NodeLayout& layout = state.sys->layout;
  const int freeNodes = layout.freeNodes();

  NodeNeighbours lower;
  const double lowerMs = MedianMs(repeats, [&] {
    lower = LowerNodeNeighbours(request.mesh.tets.data(), request.mesh.numTets(), 4, layout.dofNode,
                                static_cast<int>(layout.meshNode.size()));
  });
  SparseMatrix pattern;
  const double patternMs =
      MedianMs(repeats, [&] { UpperPatternOfNodes(lower, freeNodes, false, pattern); });
  std::vector<char> coupled;
  const double coupledMs =
      MedianMs(repeats, [&] { coupled = NodesCoupledToLaterNodes(lower, freeNodes); });
  FillReducingOrdering ordering;
  const double metisMs = MedianMs(repeats, [&] {
    ordering = FillReducingOrdering();
    OrderNodeGraphWithTrailing(lower, freeNodes, 3, coupled, ordering);
  });
  CholmodFactor factor;
  const std::vector<FillReducingOrdering> candidates{ordering};
  const double analyzeMs = MedianMs(repeats, [&] { factor.analyze(pattern, candidates, nullptr); });
  std::printf(
      "scene %d/%d: %ld tets, %d free nodes, K_FF %ld x %ld with %ld stored entries, factor %.3g "
      "nonzeros (%d trailing DOFs)\n",
      subdivisions, layers, static_cast<long>(request.mesh.numTets()), freeNodes,
      static_cast<long>(pattern.rows()), static_cast<long>(pattern.cols()),
      static_cast<long>(pattern.nonZeros()), factor.factorNonzeros(), factor.trailingDofs());
  // The supernodal structure the GPU response sweeps (Cuda/CudaDenseResponse): its backward sweep
  // gathers each supernode's off-diagonal rows of the right-hand-side block into a workspace and
  // reads them back in a GEMM, so with r right-hand sides it moves at least 3 * 8 r bytes per
  // off-diagonal row (read, write, read), beside 2 * 8 r per diagonal row (read and write).
  if (const cholmod_factor* L = factor.cholmodFactor(); L && L->is_super) {
    const int* super = static_cast<const int*>(L->super);
    const int* pi = static_cast<const int*>(L->pi);
    double offRows = 0.0, diagonalRows = 0.0, trsmFlops = 0.0, gemmFlops = 0.0, bigTrsmFlops = 0.0;
    const double r = 3.0 * double(request.sets.movable.size()); // the ROI DOFs: response columns
    for (size_t s = 0; s < L->nsuper; ++s) {
      const double nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
      diagonalRows += nscol;
      offRows += nsrow - nscol;
      trsmFlops += r * nscol * nscol;
      gemmFlops += 2.0 * r * nscol * (nsrow - nscol);
      if (nscol >= 256)
        bigTrsmFlops += r * nscol * nscol;
    }
    std::printf(
        "backward sweep flops: triangular solves on the diagonal blocks %.3g TFLOP (%.3g in "
        "supernodes of >= 256 columns), products with the off-diagonal blocks %.3g TFLOP\n",
        trsmFlops / 1e12, bigTrsmFlops / 1e12, gemmFlops / 1e12);
    std::printf(
        "supernodes %zu: %.3g diagonal and %.3g off-diagonal rows; with %.0f right-hand sides "
        "the backward sweep's row traffic is at least %.3g TB\n",
        L->nsuper, diagonalRows, offRows, r, 8.0 * r * (3.0 * offRows + 2.0 * diagonalRows) / 1e12);
  }
  std::printf("median of %d, ms: node graph %.0f | K_FF pattern %.0f | ROI-coupled marks %.0f | "
              "METIS ordering %.0f (%d parts) | CHOLMOD symbolic analysis %.0f | sum %.0f\n",
              repeats, lowerMs, patternMs, coupledMs, metisMs, ordering.leaves, analyzeMs,
              lowerMs + patternMs + coupledMs + metisMs + analyzeMs);
  return 0;
}
