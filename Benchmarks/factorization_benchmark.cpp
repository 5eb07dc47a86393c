// SPDX-License-Identifier: BSD-3-Clause
// The numeric factorization of K_FF alone, CHOLMOD's cholmod_factorize against the multifrontal
// one (SparseSolver/MultifrontalCholesky.h), alternated in one process on the same analysed
// matrix: medians of --repeats runs each, and the largest relative difference between the two
// factors' solutions of one right-hand side. Scene: MakeFaceLikeScene(subdivisions, layers) with
// the precompute's own stages up to the analysis (ROI-coupled DOFs last).
//   factorization_benchmark [--subdivisions 18] [--layers 5] [--repeats 7]
// 18/5 is faceplan_benchmark's ~100k scene.
#include "CondensedFEM/PrecomputeStages.h"
#include "SceneArguments.h"
#include "SparseSolver/CholmodFactor.h"
#include "Support/FEMTestScenes.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace faceplan;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int Fail(const Status& s) {
  std::fprintf(stderr, "%s\n", s.message.c_str());
  return 1;
}

} // namespace

int main(int argc, char** argv) {
  benchmarks::SceneArguments args{18, 5, 7};
  if (!benchmarks::ParseSceneArguments(argc, argv, args))
    return 2;
  const int subdivisions = args.subdivisions, layers = args.layers, repeats = args.repeats;
  const PrecomputeRequest request = benchmarks::DenseResponseScene(args);
  PrecomputeState state(request, nullptr, ProgressCallback());
  for (auto stage : {ValidatePrecomputeRequest, FinishMeshChecks, SeparateNodes, AssembleStiffness,
                     SeparateBlocks, ReorderFreeDofs})
    if (Status s = stage(state); !s)
      return Fail(s);
  const SparseMatrix& kff = state.sys->kff;
  CholmodFactor& factor = state.sys->factor;
  const Eigen::MatrixXd b = Eigen::MatrixXd::Ones(kff.rows(), 1);
  Eigen::MatrixXd x[2];
  std::vector<double> ms[2];
  const char* names[2] = {"cholmod", "multifrontal"};
  for (int r = 0; r < repeats; ++r)
    for (int m = 0; m < 2; ++m) {
      setenv("FACEPLAN_FACTORIZATION", names[m], 1);
      const auto t0 = std::chrono::steady_clock::now();
      if (Status s = factor.factorize(kff); !s)
        return Fail(s);
      ms[m].push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (r == 0)
        if (Status s = factor.solve(b, x[m]); !s)
          return Fail(s);
    }
  std::printf("scene %d/%d: K_FF %ld x %ld, factor %.4g nonzeros, %.4g GFLOP\n", subdivisions,
              layers, long(kff.rows()), long(kff.cols()), factor.factorNonzeros(),
              factor.factorFlops() * 1e-9);
  for (int m = 0; m < 2; ++m) {
    std::printf("%-13s median %.1f ms over %d runs:", names[m], Median(ms[m]), repeats);
    for (double v : ms[m])
      std::printf(" %.1f", v);
    std::printf("\n");
  }
  std::printf("ratio multifrontal/cholmod %.3f; solutions differ by %.2e (relative, max norm)\n",
              Median(ms[1]) / Median(ms[0]),
              (x[1] - x[0]).cwiseAbs().maxCoeff() / x[0].cwiseAbs().maxCoeff());
  return 0;
}
