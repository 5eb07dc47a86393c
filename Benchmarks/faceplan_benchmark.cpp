// SPDX-License-Identifier: BSD-3-Clause
// FacePlan CPU benchmark on the face-like scaling family (see scripts/benchmark, which runs one
// size per process so that the peak memory figure belongs to that size alone).
//
//   faceplan_benchmark --subdivisions S --layers L [--edits N] [--precompute-repeats N]
//                      [--reference-repeats N] [--method Auto|DenseResponse|CachedFactor]
//                      [--ccx WORKDIR] [--ccx-repeats N] [--json FILE]
#include "Common/BlasKernels.h"
#include "Common/RelativeDifference.h"
#include "CondensedFEM/CondensedFEM.h"
#include "Support/CalculixRunner.h"
#include "Support/ShellMeshGenerator.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <sys/resource.h>
#include <thread>
#include <vector>

using namespace faceplan;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}
double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}
double PeakRssMB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

// A random surgical edit: a smooth displacement of the ROI, a few millimetres.
RowVectors3d RandomEdit(const PrecomputeRequest& r, std::mt19937& rng) {
  std::uniform_real_distribution<double> amp(-3.0, 3.0), freq(0.02, 0.08);
  const double ax = amp(rng), ay = amp(rng), az = amp(rng), f = freq(rng);
  RowVectors3d u(static_cast<Eigen::Index>(r.sets.movable.size()), 3);
  for (size_t k = 0; k < r.sets.movable.size(); ++k) {
    const Eigen::RowVector3d p = r.mesh.points.row(r.sets.movable[k]);
    u.row(k) << ax * std::sin(f * p(0)), ay * std::cos(f * p(1)),
        az * (1 + std::sin(f * (p(0) + p(1))));
  }
  return u;
}

} // namespace

int main(int argc, char** argv) {
  int subdivisions = 8, layers = 3, edits = 200, precomputeRepeats = 3, referenceRepeats = 1;
  std::string method = "Auto", ccxDir, jsonPath;
  int responseBlockColumns = 0; // 0: the default of PrecomputeOptions
  int ccxRepeats = 1; // CalculiX runs, median wall time (the machine is noisy, as for our repeats)
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--subdivisions")
      subdivisions = std::stoi(value);
    else if (key == "--layers")
      layers = std::stoi(value);
    else if (key == "--edits")
      edits = std::stoi(value);
    else if (key == "--precompute-repeats")
      precomputeRepeats = std::stoi(value);
    else if (key == "--reference-repeats")
      referenceRepeats = std::stoi(value);
    else if (key == "--method")
      method = value;
    else if (key == "--ccx")
      ccxDir = value;
    else if (key == "--ccx-repeats")
      ccxRepeats = std::max(1, std::stoi(value));
    else if (key == "--json")
      jsonPath = value;
    else if (key == "--response-block-columns")
      responseBlockColumns = std::max(1, std::stoi(value));
    else {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      return 2;
    }
  }
  const FaceLikeScene scene = MakeFaceLikeScene(subdivisions, layers, 0.1);
  PrecomputeRequest request;
  request.mesh = scene.shell.mesh;
  request.materials = Materials::Uniform(3.0e3, 0.45); // facial soft tissue, Pa and mm
  request.sets = {scene.constrained, scene.movable, scene.kept};
  if (method == "DenseResponse")
    request.options.method = SolveMethod::DenseResponse;
  else if (method == "CachedFactor")
    request.options.method = SolveMethod::CachedFactor;
  if (responseBlockColumns > 0)
    request.options.responseBlockColumns = responseBlockColumns;

  // Precompute (median of repeats, stage by stage).
  std::shared_ptr<const CondensedSystem> system;
  std::vector<std::vector<double>> stageMs(kNumStages);
  for (int r = 0; r < precomputeRepeats; ++r) {
    system.reset();
    const Status s = Precompute(request, system);
    if (!s) {
      std::fprintf(stderr, "precompute failed: %s\n", s.message.c_str());
      return 1;
    }
    const SystemInfo info = Describe(*system);
    for (int k = 0; k < kNumStages; ++k)
      stageMs[k].push_back(info.precomputeTimings.stages[k].ms);
  }
  const SystemInfo info = Describe(*system);

  // Per-edit updates: new ROI displacements -> kept displacements.
  std::mt19937 rng(42);
  std::vector<RowVectors3d> editInputs;
  for (int e = 0; e < std::min(edits, 16); ++e)
    editInputs.push_back(RandomEdit(request, rng));
  std::vector<double> editMs;
  SolveResult result;
  SolveInput input;
  double worstResidual = 0.0;
  for (int e = 0; e < edits; ++e) {
    input.movableDisplacement = editInputs[e % editInputs.size()];
    const Status s = Solve(*system, input, result);
    if (!s) {
      std::fprintf(stderr, "solve failed: %s\n", s.message.c_str());
      return 1;
    }
    editMs.push_back(result.timings[Stage::Total].ms);
    worstResidual = std::max(worstResidual, result.relativeResidual);
  }
  input.movableDisplacement = editInputs[0];
  Solve(*system, input, result);
  const RowVectors3d condensedKept = result.keptDisplacement;
  const double peakCondensedMB = PeakRssMB();
  system.reset();

  // Reference full solve from scratch (the paper's traditional FEM).
  std::vector<double> referenceMs;
  SolveResult reference;
  for (int r = 0; r < referenceRepeats; ++r) {
    const Status s = SolveFullReference(request, input, reference);
    if (!s) {
      std::fprintf(stderr, "reference failed: %s\n", s.message.c_str());
      return 1;
    }
    referenceMs.push_back(reference.timings[Stage::Total].ms);
  }
  const double diffReference = RelativeMaxDifference(condensedKept, reference.keptDisplacement);

  bench::CalculixResult ccx;
  double diffCcx = -1.0;
  if (!ccxDir.empty()) {
    std::vector<double> ccxMs;
    for (int r = 0; r < ccxRepeats; ++r) {
      ccx = bench::RunCalculix(request, input.movableDisplacement, ccxDir,
                               static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
      if (!ccx.ok)
        break;
      ccxMs.push_back(ccx.wallMs);
    }
    if (ccx.ok)
      ccx.wallMs = Median(ccxMs);
    if (ccx.ok)
      diffCcx = RelativeMaxDifference(condensedKept, ccx.keptDisplacement);
    else
      std::fprintf(stderr, "CalculiX: %s\n", ccx.error.c_str());
  }

  const double precomputeMs = Median(stageMs[static_cast<int>(Stage::Total)]);
  const double editMedian = Median(editMs), referenceMedian = Median(referenceMs);
  std::printf(
      "tets %lld  nodes %lld  free DOFs %lld  kept DOFs %lld  ROI DOFs %lld  method %s (%s)\n",
      static_cast<long long>(request.mesh.numTets()),
      static_cast<long long>(request.mesh.numPoints()), info.freeDofs, info.keptDofs, info.roiDofs,
      MethodName(info.method), info.choiceReason.c_str());
  std::printf(
      "precompute %.1f ms (median of %d)  per-edit %.3f ms (median of %d, p10 %.3f, p90 %.3f)\n",
      precomputeMs, precomputeRepeats, editMedian, edits, Quantile(editMs, 0.1),
      Quantile(editMs, 0.9));
  std::printf("reference full solve %.1f ms  ratio reference/edit %.0f  peak RSS (condensed) %.0f "
              "MB, (all) %.0f MB\n",
              referenceMedian, referenceMedian / editMedian, peakCondensedMB, PeakRssMB());
  std::printf("max rel. difference to reference %.2e, worst residual %.2e\n", diffReference,
              worstResidual);
  std::printf("ordering: %s; response: %s\n", info.ordering.c_str(), info.responsePath.c_str());
  // The stage rows hold the waits for these threads (last precompute's figures).
  std::printf("beside the stages: ordering thread %.1f ms (%s), mesh-check thread %.1f ms\n",
              info.orderingThreadMs, info.orderedBesideAssembly ? "beside the assembly" : "in line",
              info.meshChecksThreadMs);
  const BlasKernels blas = DescribeBlasKernels();
  std::printf("BLAS kernels: %s%s%s\n", blas.name.empty() ? "(not OpenBLAS)" : blas.name.c_str(),
              blas.advice.empty() ? "" : " -- ", blas.advice.c_str());
  if (ccx.ok)
    std::printf("CalculiX %.1f ms (median of %d), max rel. difference %.2e\n", ccx.wallMs,
                ccxRepeats, diffCcx);

  if (!jsonPath.empty()) {
    std::ofstream out(jsonPath);
    out.precision(6);
    out << "{\n  \"tets\": " << request.mesh.numTets()
        << ", \"nodes\": " << request.mesh.numPoints() << ", \"subdivisions\": " << subdivisions
        << ", \"layers\": " << layers << ",\n  \"free_dofs\": " << info.freeDofs
        << ", \"kept_dofs\": " << info.keptDofs << ", \"roi_dofs\": " << info.roiDofs
        << ", \"factor_nonzeros\": " << info.factorNonzeros << ",\n  \"method\": \""
        << MethodName(info.method) << "\", \"choice_reason\": \"" << info.choiceReason
        << "\",\n  \"precompute_repeats\": " << precomputeRepeats << ", \"precompute_stage_ms\": {";
    for (int k = 0; k < kNumStages; ++k)
      out << (k ? ", " : "") << "\"" << StageName(static_cast<Stage>(k))
          << "\": " << Median(stageMs[k]);
    out << "},\n  \"edits\": " << edits << ", \"edit_ms_median\": " << editMedian
        << ", \"edit_ms_p10\": " << Quantile(editMs, 0.1)
        << ", \"edit_ms_p90\": " << Quantile(editMs, 0.9)
        << ",\n  \"reference_ms_median\": " << referenceMedian
        << ", \"reference_over_edit\": " << referenceMedian / editMedian
        << ",\n  \"peak_rss_condensed_mb\": " << peakCondensedMB
        << ", \"peak_rss_all_mb\": " << PeakRssMB()
        << ",\n  \"max_rel_diff_reference\": " << diffReference
        << ", \"worst_relative_residual\": " << worstResidual
        << ",\n  \"ccx_ms\": " << (ccx.ok ? ccx.wallMs : -1.0)
        << ", \"ccx_repeats\": " << ccxRepeats << ", \"max_rel_diff_ccx\": " << diffCcx
        << ",\n  \"ordering\": \"" << info.ordering << "\", \"response_path\": \""
        << info.responsePath << "\", \"blas_kernels\": \"" << blas.name
        << "\",\n  \"ordering_thread_ms\": " << info.orderingThreadMs
        << ", \"mesh_checks_thread_ms\": " << info.meshChecksThreadMs << "\n}\n";
  }
  return 0;
}
