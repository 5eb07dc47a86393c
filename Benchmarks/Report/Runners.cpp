// SPDX-License-Identifier: BSD-3-Clause
#include "Common/RelativeDifference.h"
#include "Report/Report.h"

#include "Comparison/ConjugateGradientSolve.h"
#include "Comparison/MassSpringSolve.h"
#include "Comparison/SinglePrecisionCholesky.h"
#include "Comparison/TraditionalBandSolve.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Support/CalculixRunner.h"

#ifdef FACEPLAN_REPORT_WITH_CUDA
#include "CudaBackend.h"
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace faceplan::report {

namespace fs = std::filesystem;

Errors Compare(const RowVectors3d& u, const RowVectors3d& reference) {
  Errors e;
  if (u.rows() != reference.rows() || u.rows() == 0)
    return e;
  const Eigen::VectorXd diff = (u - reference).rowwise().norm(), ref = reference.rowwise().norm();
  const double n = double(u.rows());
  e.maxAbs = diff.maxCoeff();
  e.rmsAbs = std::sqrt(diff.squaredNorm() / n);
  const double refMax = ref.maxCoeff(), refRms = std::sqrt(ref.squaredNorm() / n);
  e.maxRel = refMax > 0 ? RelativeMaxNodeDifference(u, reference) : kNaN;
  e.rmsRel = refRms > 0 ? e.rmsAbs / refRms : kNaN;
  return e;
}

void Report::runReference(Scene& s) {
  SolveInput input;
  input.movableDisplacement = s.edit;
  input.recoverInterior = s.analytic;
  SolveResult result;
  std::vector<double> ms;
  for (int k = 0; k < repeatsFor(s); ++k) {
    const double t0 = NowMs();
    const Status st = SolveFullReference(s.request, input, result);
    ms.push_back(NowMs() - t0);
    if (!st) {
      referenceKept_.resize(0, 3);
      notRun(s, "reference (full sparse direct, double)", "failed: " + st.message);
      return;
    }
  }
  referenceKept_ = result.keptDisplacement;
  Row r;
  r.path = "reference (full sparse direct, double)";
  r.variant = "CHOLMOD";
  r.precompute = Summarize({0.0});
  r.edit = Summarize(ms);
  r.residual = result.relativeResidual;
  setErrors(s, r, result.keptDisplacement, s.analytic ? &result.allDisplacement : nullptr);
  r.note = "no cache: every edit assembles, factors and solves";
  add(s, r);
}

void Report::runCondensed(Scene& s) {
  SolveInput input;
  input.movableDisplacement = s.edit;
  // Auto first: its precompute counts as one repeat of the method it picks.
  std::shared_ptr<const CondensedSystem> autoSystem;
  PrecomputeRequest request = s.request;
  request.options.method = SolveMethod::Auto;
  double autoMs = 0;
  {
    const double t0 = NowMs();
    const Status st = Precompute(request, autoSystem);
    autoMs = NowMs() - t0;
    if (!st) {
      notRun(s, "condensed (Auto)", "precompute failed: " + st.message);
      return;
    }
  }
  const SystemInfo autoInfo = Describe(*autoSystem);
  AutoChoice choice;
  choice.scene = s.name;
  choice.method = MethodName(autoInfo.method);
  choice.reason = autoInfo.choiceReason;
  sceneStats_[s.name]["free_dofs"] = double(autoInfo.freeDofs);
  sceneStats_[s.name]["kept_dofs"] = double(autoInfo.keptDofs);
  sceneStats_[s.name]["roi_dofs"] = double(autoInfo.roiDofs);
  sceneStats_[s.name]["factor_nnz"] = autoInfo.factorNonzeros;

  for (SolveMethod method : {SolveMethod::CachedFactor, SolveMethod::DenseResponse}) {
    const std::string path =
        method == SolveMethod::CachedFactor ? "condensed CachedFactor" : "condensed DenseResponse";
    if (method == SolveMethod::DenseResponse) {
      const double bytes = 8.0 * double(autoInfo.keptDofs) * double(autoInfo.roiDofs);
      if (bytes > 2.0e9) {
        notRun(s, path, "dense response would take " + std::to_string(int(bytes / 1e6)) + " MB");
        continue;
      }
      const double solveFlops = 4.0 * autoInfo.factorNonzeros * double(autoInfo.roiDofs);
      if (autoInfo.method != method && solveFlops > 3e10 && !cfg_.large) {
        char why[160];
        std::snprintf(why, sizeof why,
                      "not Auto's choice and its precompute needs %.0f column solves (~%.0f "
                      "GFLOP); --large runs it",
                      double(autoInfo.roiDofs), solveFlops / 1e9);
        notRun(s, path, why);
        continue;
      }
    }
    std::vector<double> pre;
    std::vector<std::vector<double>> stage(kNumStages);
    std::shared_ptr<const CondensedSystem> system;
    request.options.method = method;
    if (autoInfo.method == method) {
      system = autoSystem;
      pre.push_back(autoMs);
      for (int k = 0; k < kNumStages; ++k)
        stage[k].push_back(autoInfo.precomputeTimings.stages[k].ms);
    }
    bool failed = false;
    while (static_cast<int>(pre.size()) < repeatsFor(s)) {
      std::shared_ptr<const CondensedSystem> fresh;
      system.reset();
      const double t0 = NowMs();
      const Status st = Precompute(request, fresh);
      pre.push_back(NowMs() - t0);
      if (!st) {
        notRun(s, path, "precompute failed: " + st.message);
        failed = true;
        break;
      }
      system = fresh;
      const SystemInfo info = Describe(*system);
      for (int k = 0; k < kNumStages; ++k)
        stage[k].push_back(info.precomputeTimings.stages[k].ms);
    }
    if (failed)
      continue;
    std::vector<double> edit, boundary, solve;
    SolveResult result;
    const int edits = s.large ? std::max(5, cfg_.edits / 2) : cfg_.edits;
    for (int e = 0; e < edits; ++e) {
      const double t0 = NowMs();
      const Status st = Solve(*system, input, result);
      edit.push_back(NowMs() - t0);
      if (!st) {
        notRun(s, path, "solve failed: " + st.message);
        failed = true;
        break;
      }
      boundary.push_back(result.timings[Stage::BoundaryCondition].ms);
      solve.push_back(result.timings[Stage::Solve].ms);
    }
    if (failed)
      continue;
    Row r;
    r.path = path;
    r.variant = "double";
    r.precompute = Summarize(pre);
    r.edit = Summarize(edit);
    r.residual = result.relativeResidual;
    RowVectors3d all;
    if (s.analytic && method == SolveMethod::CachedFactor) {
      SolveInput full = input;
      full.recoverInterior = true;
      SolveResult fullResult;
      if (Solve(*system, full, fullResult))
        all = fullResult.allDisplacement;
    }
    setErrors(s, r, result.keptDisplacement, all.rows() ? &all : nullptr);
    if (autoInfo.method == method)
      r.note = "Auto's choice";
    add(s, r);
    if (method == SolveMethod::DenseResponse) {
      choice.denseEdit = r.edit.median;
      choice.densePre = r.precompute.median;
    } else {
      choice.factorEdit = r.edit.median;
      choice.factorPre = r.precompute.median;
    }
    if (s.name == "mandible" && method == autoInfo.method) {
      table2_.ourMethod = MethodName(method);
      auto st = [&](Stage x) { return Summarize(stage[static_cast<int>(x)]); };
      table2_.oReordering = st(Stage::Reordering);
      table2_.oElement = st(Stage::ElementStiffness);
      table2_.oAssembly = st(Stage::Assembly);
      table2_.oSeparation = st(Stage::Separation);
      table2_.oFactorization = st(Stage::Factorization);
      table2_.oCondensation = st(Stage::Condensation);
      table2_.oPrecomputeTotal = Summarize(pre);
      table2_.oBoundary = Summarize(boundary);
      table2_.oSolve = Summarize(solve);
      table2_.oEdit = Summarize(edit);
    }
  }
  autos_.push_back(choice);
}

void Report::runIterative(Scene& s, const FreeSystem& fs, double assembleMs) {
  Eigen::VectorXd roi;
  if (!RoiVector(fs, s.edit, roi))
    return;
  const Eigen::VectorXd rhs = FreeRightHandSide(fs, roi);
  const Eigen::VectorXd previousRhs = 0.95 * rhs; // the previous step of a drag, for warm starts
  const int reps = s.large ? 1 : std::min(cfg_.repeats, 3);
  struct Variant {
    CGPreconditioner pre;
    CGPrecision precision;
    std::vector<double> tolerances;
    int maxIterations;
  };
  const std::vector<double> all = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  const std::vector<Variant> variants = {
      {CGPreconditioner::IncompleteCholesky, CGPrecision::Double, all, 20000},
      {CGPreconditioner::Jacobi, CGPrecision::Double, {1e-2, 1e-4, 1e-6, 1e-8, 1e-10}, 20000},
      {CGPreconditioner::IncompleteCholesky,
       CGPrecision::Single,
       {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7},
       5000},
  };
  for (const Variant& v : variants) {
    const bool single = v.precision == CGPrecision::Single;
    const std::string path =
        std::string(single ? "PCG float " : "PCG ") + CGPreconditionerName(v.pre);
    ConjugateGradientSolver cg;
    CGOptions options;
    options.preconditioner = v.pre;
    options.precision = v.precision;
    options.maxIterations = v.maxIterations;
    std::vector<double> setup;
    Status st;
    for (int k = 0; k < reps && st; ++k) {
      st = cg.setup(fs, options);
      setup.push_back(assembleMs + cg.setupMs());
    }
    if (!st) {
      notRun(s, path, "setup failed: " + st.message);
      continue;
    }
    // Times `reps` solves from `guess` (a slow one, over 300 ms, only once: keeps the run short).
    auto timeSolves = [&](double tol, const Eigen::VectorXd* guess, Eigen::VectorXd& x,
                          CGReport& report, std::vector<double>& ms) {
      Status solved;
      for (int k = 0; k < reps; ++k) {
        const double t0 = NowMs();
        solved = cg.solve(rhs, tol, guess, x, report);
        ms.push_back(NowMs() - t0);
        if (!solved || ms.back() > 300.0)
          break;
      }
      return solved;
    };
    // A PCG row's times, iterations, residual and errors from its timed solves.
    auto fillRow = [&](Row& r, const std::vector<double>& ms, const CGReport& report,
                       const Eigen::VectorXd& x) {
      r.precompute = Summarize(setup);
      r.edit = Summarize(ms);
      r.iterations = report.iterations;
      r.converged = report.converged ? 1 : 0;
      r.residual = report.relativeResidual;
      const RowVectors3d allU = s.analytic ? AllDisplacement(fs, x, roi) : RowVectors3d();
      setErrors(s, r, KeptDisplacement(fs, x, roi), s.analytic ? &allU : nullptr);
    };
    bool stalled = false;
    for (double tol : v.tolerances) {
      Row r;
      r.path = path;
      char buf[32];
      std::snprintf(buf, sizeof buf, "tol %.0e", tol);
      r.variant = buf;
      r.tolerance = tol;
      if (stalled) {
        r.ran = false;
        r.note = "not run: the previous tolerance already hit the iteration cap";
        add(s, r);
        continue;
      }
      std::vector<double> ms;
      Eigen::VectorXd x;
      CGReport report;
      st = timeSolves(tol, nullptr, x, report, ms);
      if (!st) {
        r.ran = false;
        r.note = "failed: " + st.message;
        add(s, r);
        continue;
      }
      fillRow(r, ms, report, x);
      r.note = std::to_string(report.iterations) + " iterations" +
               (report.converged ? "" : ", NOT converged (cap)");
      if (!report.converged)
        stalled = true;
      add(s, r);
    }
    // Warm start from the previous drag step's solution (double IC only).
    if (!single && v.pre == CGPreconditioner::IncompleteCholesky) {
      for (double tol : {1e-6, 1e-10}) {
        Eigen::VectorXd guess, x;
        CGReport report;
        if (!cg.solve(previousRhs, tol, nullptr, guess, report))
          continue;
        std::vector<double> ms;
        st = timeSolves(tol, &guess, x, report, ms);
        if (!st)
          continue;
        Row r;
        r.path = "PCG IncompleteCholesky warm";
        char buf[32];
        std::snprintf(buf, sizeof buf, "tol %.0e", tol);
        r.variant = buf;
        r.tolerance = tol;
        fillRow(r, ms, report, x);
        r.note = std::to_string(report.iterations) +
                 " iterations, started from the previous drag step (edit x 0.95)";
        add(s, r);
      }
    }
  }
}

void Report::runSingleDirect(Scene& s, const FreeSystem& fs, double assembleMs) {
  Eigen::VectorXd roi;
  if (!RoiVector(fs, s.edit, roi))
    return;
  const Eigen::VectorXd rhs = FreeRightHandSide(fs, roi);
  if (s.request.mesh.numTets() > 40000 && !cfg_.large)
    return notRun(s, "float Cholesky (Eigen SimplicialLLT)",
                  "Eigen's simplicial (non-supernodal, one-thread) float factorization takes tens "
                  "of seconds above 40k tets; --large runs it");
  SinglePrecisionCholesky llt;
  std::vector<double> pre;
  Status st;
  const int reps = s.large ? 1 : std::min(cfg_.repeats, 3);
  for (int k = 0; k < reps && st; ++k) {
    st = llt.factorize(fs);
    pre.push_back(assembleMs + llt.factorizeMs());
  }
  if (!st) {
    notRun(s, "float Cholesky (Eigen SimplicialLLT)", st.message);
    return;
  }
  for (int steps : {0, 2}) {
    std::vector<double> ms;
    Eigen::VectorXd x;
    SinglePrecisionReport report;
    for (int k = 0; k < cfg_.edits && st; ++k) {
      const double t0 = NowMs();
      st = llt.solve(rhs, steps, x, report);
      ms.push_back(NowMs() - t0);
    }
    if (!st) {
      notRun(s, "float Cholesky", st.message);
      return;
    }
    Row r;
    r.path = steps == 0 ? "float Cholesky" : "float Cholesky + 2 refinements";
    r.variant = steps == 0 ? "single" : "mixed";
    r.precompute = Summarize(pre);
    r.edit = Summarize(ms);
    r.residual = report.relativeResidual;
    const RowVectors3d allU = s.analytic ? AllDisplacement(fs, x, roi) : RowVectors3d();
    setErrors(s, r, KeptDisplacement(fs, x, roi), s.analytic ? &allU : nullptr);
    r.note = steps == 0 ? "Eigen SimplicialLLT<float>, AMD ordering, one thread"
                        : "float factor, residuals in double (iterative refinement)";
    add(s, r);
  }
}

void Report::runBand(Scene& s) {
  const std::string path = "traditional band Cholesky (RCM, 1 thread)";
  TraditionalBandOptions options;
  options.maxFactorFlops = cfg_.bandMaxGflop * 1e9;
  options.recoverAll = s.analytic;
  std::vector<double> total, reo, el, as, bc, fa, so;
  TraditionalBandResult band;
  const int reps = s.large ? 1 : std::min(cfg_.repeats, 3);
  for (int k = 0; k < reps; ++k) {
    const Status st = SolveTraditionalBand(s.request, s.edit, band, options);
    if (!st) {
      notRun(s, path, st.message);
      return;
    }
    total.push_back(band.totalMs);
    reo.push_back(band.reorderingMs);
    el.push_back(band.elementStiffnessMs);
    as.push_back(band.assemblyMs);
    bc.push_back(band.boundaryConditionMs);
    fa.push_back(band.factorizationMs);
    so.push_back(band.solveMs);
  }
  Row r;
  r.path = path;
  r.variant = "LAPACK dpbtrf";
  r.precompute = Summarize({0.0});
  r.edit = Summarize(total);
  r.residual = band.relativeResidual;
  setErrors(s, r, band.keptDisplacement, s.analytic ? &band.allDisplacement : nullptr);
  std::ostringstream note;
  note << "semi-bandwidth " << band.semiBandwidth << " DOFs (natural order "
       << band.semiBandwidthBefore << "), band " << std::fixed;
  note.precision(1);
  note << band.bandBytes / 1e6 << " MB; no cache";
  r.note = note.str();
  add(s, r);
  if (s.name == "mandible") {
    table2_.have = true;
    table2_.scene = s.name;
    table2_.tets = s.request.mesh.numTets();
    table2_.freeDofs = band.freeDofs;
    table2_.band = band.semiBandwidth;
    table2_.bandBefore = band.semiBandwidthBefore;
    table2_.reordering = Summarize(reo);
    table2_.element = Summarize(el);
    table2_.assembly = Summarize(as);
    table2_.bc = Summarize(bc);
    table2_.factorization = Summarize(fa);
    table2_.solve = Summarize(so);
    table2_.total = Summarize(total);
  }
}

void Report::runCalculix(Scene& s) {
  const std::string path = "CalculiX ccx (C3D4)";
  if (!cfg_.ccx)
    return notRun(s, path, "--no-ccx");
  if (std::system("command -v ccx > /dev/null 2>&1") != 0)
    return notRun(s, path, "ccx not installed");
  if (s.request.mesh.numTets() > 150000)
    return notRun(s, path, "over 150k tets (slow; run with the benchmark)");
  const std::string dir = (fs::path(cfg_.outDir) / "ccx" / s.name).string();
  fs::create_directories(dir);
  const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const bench::CalculixResult ccx = bench::RunCalculix(s.request, s.edit, dir, threads);
  if (!ccx.ok)
    return notRun(s, path, ccx.error);
  Row r;
  r.path = path;
  r.variant = std::to_string(threads) + " threads";
  r.precompute = Summarize({0.0});
  r.edit = Summarize({ccx.wallMs});
  setErrors(s, r, ccx.keptDisplacement, nullptr);
  r.note = "whole ccx run incl. its input parsing and .dat output (7 significant digits, so ~1e-6 "
           "is its floor)";
  add(s, r);
}

void Report::runMassSpring(Scene& s) {
  const std::string path = "mass-spring (edge springs)";
  MassSpringModel model;
  std::vector<double> pre;
  Status st;
  for (int k = 0; k < repeatsFor(s) && st; ++k) {
    const double t0 = NowMs();
    st = model.build(s.request);
    pre.push_back(NowMs() - t0);
  }
  if (!st)
    return notRun(s, path, st.message);
  std::vector<double> ms;
  RowVectors3d kept, all;
  for (int k = 0; k < cfg_.edits && st; ++k) {
    const double t0 = NowMs();
    st = model.solve(s.edit, kept);
    ms.push_back(NowMs() - t0);
  }
  if (!st)
    return notRun(s, path, st.message);
  if (s.analytic)
    model.solve(s.edit, kept, &all);
  Row r;
  r.path = path;
  r.variant = "linearised";
  r.precompute = Summarize(pre);
  r.edit = Summarize(ms);
  setErrors(s, r, kept, s.analytic ? &all : nullptr);
  r.note = std::to_string(model.springs()) +
           " springs, k = E * sum(V) / L^2; a different model (no Poisson effect)";
  add(s, r);
}

void Report::runCuda(Scene& s) {
#ifdef FACEPLAN_REPORT_WITH_CUDA
  std::string why;
  if (!cuda::DeviceAvailable(&why))
    return notRun(s, "CUDA (condensed, GPU backend)", "no GPU: " + why);
  std::shared_ptr<ComputeBackend> backend;
  const Status made = cuda::MakeCudaBackend(backend);
  if (!made)
    return notRun(s, "CUDA (condensed, GPU backend)", made.message);
  SolveInput input;
  input.movableDisplacement = s.edit;
  for (SolveMethod method : {SolveMethod::CachedFactor, SolveMethod::DenseResponse}) {
    const std::string path = std::string("CUDA condensed ") + MethodName(method);
    PrecomputeRequest request = s.request;
    request.options.method = method;
    request.options.backend = backend;
    std::vector<double> pre;
    std::shared_ptr<const CondensedSystem> system;
    Status st;
    for (int k = 0; k < repeatsFor(s) && st; ++k) {
      system.reset();
      const double t0 = NowMs();
      st = Precompute(request, system);
      pre.push_back(NowMs() - t0);
    }
    if (!st) {
      notRun(s, path, st.message);
      continue;
    }
    std::vector<double> ms;
    SolveResult result;
    for (int e = 0; e < cfg_.edits && st; ++e) {
      const double t0 = NowMs();
      st = Solve(*system, input, result);
      ms.push_back(NowMs() - t0);
    }
    if (!st) {
      notRun(s, path, st.message);
      continue;
    }
    Row r;
    r.path = path;
    r.variant = result.backend;
    r.precompute = Summarize(pre);
    r.edit = Summarize(ms);
    r.residual = result.relativeResidual;
    setErrors(s, r, result.keptDisplacement, nullptr);
    add(s, r);
  }
#else
  notRun(s, "CUDA (condensed, GPU backend)", "no GPU / built without the FacePlanCuda target");
#endif
}

void Report::run(Scene& s) {
  std::printf("\n== %s: %lld tets, %lld nodes, %zu kept, %zu ROI, %zu constrained\n   %s\n",
              s.name.c_str(), static_cast<long long>(s.request.mesh.numTets()),
              static_cast<long long>(s.request.mesh.numPoints()), s.request.sets.kept.size(),
              s.request.sets.movable.size(), s.request.sets.constrained.size(),
              s.description.c_str());
  std::fflush(stdout);
  sceneInfo_.push_back({s.name, s.description});
  auto& stats = sceneStats_[s.name];
  stats["tets"] = double(s.request.mesh.numTets());
  stats["nodes"] = double(s.request.mesh.numPoints());
  stats["h"] = s.h;
  runReference(s);
  if (referenceKept_.rows() == 0)
    return;
  runCondensed(s);
  FreeSystem fs;
  const double t0 = NowMs();
  const Status st = BuildFreeSystem(s.request, fs);
  const double assembleMs = NowMs() - t0;
  if (!st) {
    notRun(s, "PCG / float paths", "assembly failed: " + st.message);
  } else {
    runIterative(s, fs, assembleMs);
    runSingleDirect(s, fs, assembleMs);
  }
  runBand(s);
  runCalculix(s);
  runMassSpring(s);
  runCuda(s);
}

} // namespace faceplan::report
