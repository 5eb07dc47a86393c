// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The report: runs every solve path on a scene (Runners.cpp) and writes results.csv, table2.csv
// and REPORT.md (Writers.cpp).
#include "Comparison/FreeSystem.h"
#include "Report/Scenes.h"
#include "Report/Statistics.h"

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace faceplan::report {

struct Row {
  std::string scene, path, variant, note;
  double tolerance = kNaN;
  Spread precompute, edit;
  double iterations = kNaN, residual = kNaN;
  int converged = -1;
  double maxAbs = kNaN, rmsAbs = kNaN, maxRel = kNaN, rmsRel = kNaN, l2Analytic = kNaN;
  bool ran = true;
};

struct Errors {
  double maxAbs = kNaN, rmsAbs = kNaN, maxRel = kNaN, rmsRel = kNaN;
};

Errors Compare(const RowVectors3d& u, const RowVectors3d& reference);

struct Config {
  std::string outDir = "out/report", dataDir;
  bool quick = false, large = false, huge = false, ccx = true;
  int edits = 20, repeats = 3;
  double bandMaxGflop = 100.0;
  std::vector<std::string> scenes;
};

struct Table2 {
  bool have = false;
  std::string scene;
  long long tets = 0, freeDofs = 0;
  int bandBefore = 0, band = 0;
  Spread reordering, element, assembly, bc, factorization, solve, total;
  // Ours (condensed): precompute stages and per-edit.
  std::string ourMethod;
  Spread oReordering, oElement, oAssembly, oSeparation, oFactorization, oCondensation,
      oPrecomputeTotal, oBoundary, oSolve, oEdit;
};

// Each scene's Auto choice.
struct AutoChoice {
  std::string scene, method, reason;
  double denseEdit = kNaN, factorEdit = kNaN, densePre = kNaN, factorPre = kNaN;
};

class Report {
public:
  explicit Report(Config c) : cfg_(std::move(c)) {}
  void run(Scene& scene);
  void write() const;

private:
  void add(const Scene& s, Row r) {
    r.scene = s.name;
    std::printf("  %-26s %-14s pre %9.2f ms  edit %9.3f ms  maxrel %9.2e  rmsrel %9.2e%s%s\n",
                r.path.c_str(), r.variant.c_str(), r.precompute.median, r.edit.median, r.maxRel,
                r.rmsRel, r.note.empty() ? "" : "  ", r.note.c_str());
    std::fflush(stdout);
    rows_.push_back(std::move(r));
  }
  void notRun(const Scene& s, const std::string& path, const std::string& why) {
    Row r;
    r.path = path;
    r.ran = false;
    r.note = "not run: " + why;
    add(s, r);
  }
  void setErrors(const Scene& s, Row& r, const RowVectors3d& kept, const RowVectors3d* all) {
    const Errors e = Compare(kept, referenceKept_);
    r.maxAbs = e.maxAbs;
    r.rmsAbs = e.rmsAbs;
    r.maxRel = e.maxRel;
    r.rmsRel = e.rmsRel;
    if (s.analytic && all && all->rows() == s.request.mesh.numPoints()) {
      double norm;
      r.l2Analytic = HollowSphereL2Error(s.request.mesh, *all, s.exact, norm) / norm;
    }
  }
  int repeatsFor(const Scene& s) const { return s.large ? 1 : cfg_.repeats; }

  void runReference(Scene& s);
  void runCondensed(Scene& s);
  void runIterative(Scene& s, const FreeSystem& fs, double assembleMs);
  void runSingleDirect(Scene& s, const FreeSystem& fs, double assembleMs);
  void runBand(Scene& s);
  void runCalculix(Scene& s);
  void runMassSpring(Scene& s);
  void runCuda(Scene& s);

  Config cfg_;
  std::vector<Row> rows_;
  std::vector<std::pair<std::string, std::string>> sceneInfo_; // name, description line
  std::map<std::string, std::map<std::string, double>> sceneStats_;
  std::vector<AutoChoice> autos_;
  Table2 table2_;
  RowVectors3d referenceKept_;
  Eigen::VectorXd referenceRoi_;
};

} // namespace faceplan::report
