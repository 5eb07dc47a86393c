// SPDX-License-Identifier: BSD-3-Clause
// The numeric factorization of K_FF alone, CHOLMOD's cholmod_factorize against the multifrontal
// one (SparseSolver/MultifrontalCholesky.h), alternated in one process on the same analysed
// matrix: medians of --repeats runs each, and the largest relative difference between the two
// factors' solutions of one right-hand side. Scene: MakeFaceLikeScene(subdivisions, layers) with
// the precompute's own stages up to the analysis (ROI-coupled DOFs last). Then the single-precision
// factorization as the large-deformation solve makes it, each time into a new factor while the one
// before is still held: with fresh buffers each time, and with a workspace and a bin that keep them
// (MultifrontalWorkspace, FactorValueBin), alternated, with their solutions compared. Last, the
// substitution of one right-hand side with that factor, and its read rate of the factor beside a
// plain read of as many bytes.
//   factorization_benchmark [--subdivisions 18] [--layers 5] [--repeats 7]
// 18/5 is faceplan_benchmark's ~100k scene.
#include "Common/HelperThreads.h"
#include "CondensedFEM/PrecomputeStages.h"
#include "SceneArguments.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/MultifrontalWorkspace.h"
#include "SparseSolver/SinglePrecisionFactor.h"
#include "Support/FEMTestScenes.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

using namespace faceplan;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
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
      ms[m].push_back(MillisecondsSince(t0));
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

  const char* singleNames[2] = {"single, fresh", "single, kept"};
  std::vector<double> singleMs[2];
  MultifrontalWorkspace workspace;
  auto bin = std::make_shared<FactorValueBin>();
  std::unique_ptr<SinglePrecisionFactor> held[2];
  for (int r = 0; r < repeats + 1; ++r) // the first of each warms up (the kept buffers fill)
    for (int m = 0; m < 2; ++m) {
      auto made = std::make_unique<SinglePrecisionFactor>();
      const auto t0 = std::chrono::steady_clock::now();
      const Status s =
          m ? made->factorize(factor, kff, 2, &workspace, bin) : made->factorize(factor, kff);
      const double ms = MillisecondsSince(t0);
      if (!s)
        return Fail(s);
      if (r > 0)
        singleMs[m].push_back(ms);
      held[m] = std::move(made); // the factor before goes now, as a replaced solve's factor does
    }
  Eigen::VectorXd y[2];
  for (int m = 0; m < 2; ++m)
    if (Status s = held[m]->solve(b.col(0), y[m]); !s)
      return Fail(s);
  for (int m = 0; m < 2; ++m) {
    std::printf("%-13s median %.1f ms over %d runs:", singleNames[m], Median(singleMs[m]), repeats);
    for (double v : singleMs[m])
      std::printf(" %.1f", v);
    std::printf("\n");
  }
  std::printf("ratio kept/fresh %.3f; kept between factorizations: update buffers %.1f MB, values "
              "%.1f MB; solutions differ by %.2e (relative, max norm)\n",
              Median(singleMs[1]) / Median(singleMs[0]), workspace.keptBytes() * 1e-6,
              bin->keptBytes() * 1e-6,
              (y[1] - y[0]).cwiseAbs().maxCoeff() / y[0].cwiseAbs().maxCoeff());

  // The substitution of one right-hand side with the single-precision factor: back to back, and
  // after 64 MB of other memory was read (as in a solve, where the force evaluation and the L-BFGS
  // vectors pass between two substitutions), alternated. Beside them, after 64 MB read too, a plain
  // read of as many bytes as the factor's non-zeros take in single precision, on one thread and
  // split over two (as the substitution splits its two sides): the substitution reads each non-zero
  // twice, once a sweep, so its read rate against the plain one says how near it comes to what the
  // memory gives.
  {
    std::vector<double> flush(8u << 20, 1.0);
    double sink = 0.0;
    auto readFlush = [&] {
      for (size_t i = 0; i < flush.size(); i += 8)
        sink += flush[i];
    };
    const size_t words = static_cast<size_t>(factor.factorNonzeros());
    const double bytes = 4.0 * static_cast<double>(words);
    std::vector<std::uint32_t> plain(words, 1u);
    std::uint32_t plainSink = 0;
    auto readPlain = [&](int threads) {
      std::uint32_t part[2] = {0u, 0u};
      RunOnHelpers(threads, [&](int q) {
        const size_t begin = words * q / threads, end = words * (q + 1) / threads;
        std::uint32_t sum = 0u; // integer: the compiler may vectorize the sum
        for (size_t i = begin; i < end; ++i)
          sum += plain[i];
        part[q] = sum;
      });
      plainSink += part[0] + part[1];
    };
    std::vector<double> subMs[2], plainMs[2];
    Eigen::VectorXd z;
    for (int r = 0; r < 5 * repeats + 1; ++r) {
      for (int m = 0; m < 2; ++m) {
        if (m == 1)
          readFlush();
        const auto t0 = std::chrono::steady_clock::now();
        if (Status s = held[1]->solve(b.col(0), z); !s)
          return Fail(s);
        const double ms = MillisecondsSince(t0);
        if (r > 0)
          subMs[m].push_back(ms);
      }
      for (int m = 0; m < 2; ++m) {
        readFlush();
        const auto t0 = std::chrono::steady_clock::now();
        readPlain(m + 1);
        const double ms = MillisecondsSince(t0);
        if (r > 0)
          plainMs[m].push_back(ms);
      }
    }
    std::printf("single-precision substitution, one right-hand side: back to back median %.2f ms, "
                "after reading 64 MB %.2f ms (%d runs each)%s\n",
                Median(subMs[0]), Median(subMs[1]), 5 * repeats, sink == 0.5 ? " " : "");
    std::printf("after reading 64 MB, its reads of the factor's %.1f MB of non-zeros, twice: %.1f "
                "GB/s; a plain read of as many bytes, alternated with it: %.1f GB/s on one thread, "
                "%.1f GB/s on two%s\n",
                bytes * 1e-6, 2.0 * bytes / (Median(subMs[1]) * 1e6),
                bytes / (Median(plainMs[0]) * 1e6), bytes / (Median(plainMs[1]) * 1e6),
                plainSink == 1u ? " " : "");
  }
  return 0;
}
