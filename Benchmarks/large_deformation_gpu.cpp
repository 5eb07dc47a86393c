// SPDX-License-Identifier: BSD-3-Clause
// The precomputed large-deformation solve with the CPU and the CUDA backend side by side, on the
// face-like shell (MakeFaceLikeScene, --subdivisions 18 --layers 5: 97,200 tetrahedra): the
// precompute, the whole move from rest, then a paused drag (each step's background refactorization
// awaited before the next, as a surgeon's pauses between edits allow) of --steps steps that change
// the ROI field's amplitude by --step. Per step: wall time, iterations, force evaluations and
// substitutions and their times, the set-up and finish around the iterations; medians per
// backend; and the two backends' final results against each other.
//
// FACEPLAN_PRINT_CONVERGENCE=1 prints each step's residuals and their times.
// build/bin/large_deformation_gpu [--subdivisions S] [--layers L] [--amplitude A] [--step D]
//                                 [--steps N] [--single-precision-factor 0|1]
//                                 [--factor-ahead 0|1|2] [--ahead-corrections N] [--rigid 0|1]
//                                 [--cpu 0|1] [--json FILE]
#include "Common/RelativeDifference.h"
#include "Common/StageTimings.h"
#include "CondensedFEM/PrecomputedLargeDeformation.h"
#include "Support/FEMTestScenes.h"

#if FACEPLAN_HAS_CUDA
#include "CudaBackend.h"
#endif

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

using namespace faceplan;

namespace {

double Median(std::vector<double> v) {
  if (v.empty())
    return 0.0;
  std::sort(v.begin(), v.end());
  const size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct Step {
  double wallMs = 0.0, forcesMs = 0.0, substitutionsMs = 0.0, setupMs = 0.0, finishMs = 0.0;
  int iterations = 0, evaluations = 0, substitutions = 0;
};

struct Run {
  std::string backend;
  double precomputeMs = 0.0, fullMoveMs = 0.0;
  int fullMoveIterations = 0, fullMoveRefactorizations = 0;
  std::vector<Step> steps;
  SolveResult last;
  std::string note;
  bool ok = false;
};

Step StepOf(double wallMs, const SolveResult& r, const PrecomputedLargeDeformationReport& rep) {
  Step s;
  s.wallMs = wallMs;
  s.forcesMs = r.timings[Stage::ElementStiffness].ms;
  s.substitutionsMs = r.timings[Stage::Solve].ms;
  s.setupMs = rep.setupMs;
  s.finishMs = rep.finishMs;
  s.iterations = rep.iterations;
  s.evaluations = rep.evaluations;
  s.substitutions = rep.factorSolves;
  return s;
}

// The ROI's move: the smooth field (a bending of the cap, with shear inside it), or with --rigid 1
// a translation of the whole cap by `amplitude` along (0.3, 0.2, -1), as a bone segment moves.
bool rigidMove = false;

SolveInput Move(const PrecomputeRequest& request, double amplitude) {
  SolveInput in;
  if (rigidMove) {
    in.movableDisplacement.resize(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
    in.movableDisplacement.rowwise() = amplitude * Eigen::RowVector3d(0.3, 0.2, -1.0).normalized();
  } else {
    in.movableDisplacement = testing::SmoothRoiField(request, amplitude);
  }
  in.recoverInterior = true;
  return in;
}

Run Measure(PrecomputeRequest request, std::shared_ptr<ComputeBackend> backend, double amplitude,
            double step, int steps, const PrecomputedLargeDeformationOptions& options) {
  Run run;
  request.options.backend = backend;
  std::shared_ptr<LargeDeformationSystem> system;
  double t0 = NowMs();
  Status s = PrecomputeLargeDeformation(request, options, system);
  run.precomputeMs = NowMs() - t0;
  if (!s) {
    run.note = s.message;
    return run;
  }
  if (backend)
    std::printf("%s: factor on the device: %s\n", backend->name().c_str(),
                DescribeFactorOnDevice(*system).c_str());
  SolveResult result;
  PrecomputedLargeDeformationReport report;
  LargeDeformationState state, next;
  t0 = NowMs();
  s = SolvePrecomputedLargeDeformation(*system, Move(request, amplitude), nullptr, result, report,
                                       &state);
  run.fullMoveMs = NowMs() - t0;
  run.fullMoveIterations = report.iterations;
  run.fullMoveRefactorizations = report.refactorizations;
  run.backend = report.device;
  if (!s || report.fellBack) {
    run.note = s ? "fell back: " + report.fallbackReason : s.message;
    return run;
  }
  for (int k = 1; k <= steps; ++k) {
    WaitForRefactorization(*system);
    const SolveInput input = Move(request, amplitude + k * step);
    t0 = NowMs();
    s = SolvePrecomputedLargeDeformation(*system, input, &state, result, report, &next);
    const double ms = NowMs() - t0;
    if (!s || report.fellBack) {
      run.note = s ? "fell back: " + report.fallbackReason : s.message;
      return run;
    }
    if (!report.deviceNote.empty())
      run.note = report.deviceNote;
    state = next;
    run.steps.push_back(StepOf(ms, result, report));
    if (std::getenv("FACEPLAN_PRINT_CONVERGENCE")) {
      std::printf("    background factors so far %d (%d ahead refused, %d corrected); residuals:",
                  BackgroundRefactorizations(*system), FactorsAheadRefused(*system),
                  FactorsAheadCorrected(*system));
      for (const auto& [at, residual] : report.convergence)
        std::printf(" %.1e (%.1f ms)", residual, at);
      std::printf("; solve total %.1f ms\n", result.timings[Stage::Total].ms);
    }
  }
  StopRefactorization(*system);
  run.last = result;
  run.ok = true;
  return run;
}

void Print(const Run& r) {
  std::printf(
      "%s: precompute %.0f ms, full move %.0f ms (%d iterations, %d refactorizations)%s%s\n",
      r.backend.c_str(), r.precomputeMs, r.fullMoveMs, r.fullMoveIterations,
      r.fullMoveRefactorizations, r.note.empty() ? "" : "; ", r.note.c_str());
  std::vector<double> wall, forces, subs;
  for (size_t k = 0; k < r.steps.size(); ++k) {
    const Step& s = r.steps[k];
    std::printf("  step %zu: %.2f ms, %d iterations, %d evaluations (%.2f ms), %d substitutions "
                "(%.2f ms), set-up %.2f ms, finish %.2f ms, the rest %.2f ms\n",
                k + 1, s.wallMs, s.iterations, s.evaluations, s.forcesMs, s.substitutions,
                s.substitutionsMs, s.setupMs, s.finishMs,
                s.wallMs - s.forcesMs - s.substitutionsMs - s.setupMs - s.finishMs);
    wall.push_back(s.wallMs);
    if (s.evaluations)
      forces.push_back(s.forcesMs / s.evaluations);
    if (s.substitutions)
      subs.push_back(s.substitutionsMs / s.substitutions);
  }
  std::printf("  drag step median %.2f ms; per force evaluation %.3f ms, per substitution %.3f ms "
              "(medians)\n",
              Median(wall), Median(forces), Median(subs));
}

void Json(std::FILE* f, const Run& r) {
  std::vector<double> wall;
  std::fprintf(f,
               "{\"backend\": \"%s\", \"precompute_ms\": %.3f, \"full_move_ms\": %.3f, "
               "\"full_move_iterations\": %d, \"steps\": [",
               r.backend.c_str(), r.precomputeMs, r.fullMoveMs, r.fullMoveIterations);
  for (size_t k = 0; k < r.steps.size(); ++k) {
    const Step& s = r.steps[k];
    wall.push_back(s.wallMs);
    std::fprintf(f,
                 "%s{\"ms\": %.3f, \"iterations\": %d, \"evaluations\": %d, \"forces_ms\": %.3f, "
                 "\"substitutions\": %d, \"substitutions_ms\": %.3f}",
                 k ? ", " : "", s.wallMs, s.iterations, s.evaluations, s.forcesMs, s.substitutions,
                 s.substitutionsMs);
  }
  std::fprintf(f, "], \"drag_step_median_ms\": %.3f}", Median(wall));
}

} // namespace

int main(int argc, char** argv) {
  int subdivisions = 18, layers = 5, steps = 8;
  double amplitude = 2.5, step = 0.25;
  std::string json;
  PrecomputedLargeDeformationOptions options;
  bool skipCpu = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--single-precision-factor")
      options.singlePrecisionFactor = std::atoi(argv[i + 1]) != 0;
    else if (a == "--factor-ahead") { // 0: at the converged state; 1 or 2: the order ahead
      options.factorAhead = std::atoi(argv[i + 1]) > 0;
      options.factorAheadOrder = std::max(1, std::min(2, std::atoi(argv[i + 1])));
    } else if (a == "--ahead-corrections")
      options.aheadCorrections = std::atoi(argv[i + 1]);
    else if (a == "--rigid")
      rigidMove = std::atoi(argv[i + 1]) != 0;
    else if (a == "--cpu" && std::atoi(argv[i + 1]) == 0)
      skipCpu = true;
    else if (a == "--subdivisions")
      subdivisions = std::atoi(argv[i + 1]);
    else if (a == "--layers")
      layers = std::atoi(argv[i + 1]);
    else if (a == "--amplitude")
      amplitude = std::atof(argv[i + 1]);
    else if (a == "--step")
      step = std::atof(argv[i + 1]);
    else if (a == "--steps")
      steps = std::atoi(argv[i + 1]);
    else if (a == "--json")
      json = argv[i + 1];
    else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  const PrecomputeRequest request = testing::ShellRequest(subdivisions, layers);
  const Eigen::MatrixXd a = Move(request, amplitude).movableDisplacement,
                        b = Move(request, amplitude + step).movableDisplacement;
  std::printf("shell: %lld tetrahedra, %lld nodes, %zu ROI nodes; move: largest ROI displacement "
              "%.2f mm, a drag step changes it by up to %.2f mm\n",
              static_cast<long long>(request.mesh.numTets()),
              static_cast<long long>(request.mesh.numPoints()), request.sets.movable.size(),
              a.rowwise().norm().maxCoeff(), (b - a).rowwise().norm().maxCoeff());
  std::vector<Run> runs;
  if (!skipCpu) {
    runs.push_back(Measure(request, nullptr, amplitude, step, steps, options));
    Print(runs.back());
  }
#if FACEPLAN_HAS_CUDA
  std::shared_ptr<ComputeBackend> gpu;
  const Status made = cuda::MakeCudaBackend(gpu);
  if (made) {
    runs.push_back(Measure(request, gpu, amplitude, step, steps, options));
    Print(runs.back());
    if (runs.size() == 2 && runs[0].ok && runs[1].ok) {
      std::printf(
          "CPU against CUDA, final state: relative max node difference %.2e; CPU ÷ CUDA "
          "drag step %.1fx\n",
          RelativeMaxNodeDifference(runs[0].last.allDisplacement, runs[1].last.allDisplacement),
          Median([&] {
            std::vector<double> v;
            for (const Step& s : runs[0].steps)
              v.push_back(s.wallMs);
            return v;
          }()) /
              Median([&] {
                std::vector<double> v;
                for (const Step& s : runs[1].steps)
                  v.push_back(s.wallMs);
                return v;
              }()));
    }
  } else {
    std::printf("CUDA: skipped (%s)\n", made.message.c_str());
  }
#else
  std::printf("CUDA: skipped (this build has no CUDA backend)\n");
#endif
  if (!json.empty()) {
    std::FILE* f = std::fopen(json.c_str(), "w");
    if (!f)
      return 1;
    std::fprintf(f, "{\"tetrahedra\": %lld, \"runs\": [",
                 static_cast<long long>(request.mesh.numTets()));
    for (size_t k = 0; k < runs.size(); ++k) {
      if (k)
        std::fprintf(f, ", ");
      Json(f, runs[k]);
    }
    std::fprintf(f, "]}\n");
    std::fclose(f);
  }
  for (const Run& r : runs)
    if (!r.ok)
      return 1;
  return 0;
}
