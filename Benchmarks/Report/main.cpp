// SPDX-License-Identifier: BSD-3-Clause
// Error against run time: every solve path on a set of scenes, errors against the
// double-precision reference (and, for the hollow sphere, against the analytic solution), times
// split into precompute and per edit (medians of repeats with their spread). Writes results.csv,
// table2.csv, REPORT.md (plots are made by scripts/report_plots.py; see scripts/report).
//
//   faceplan_report [--out DIR] [--data DIR] [--quick] [--large] [--huge] [--no-ccx]
//                   [--edits N] [--repeats N] [--scenes a,b,...] [--band-max-gflop X]
//
// --quick: small scenes only (a smoke run); --large: adds the fifth sphere refinement and runs the
// paths the default run skips as too slow for a shared two-core machine (a non-Auto dense response
// over ~3e10 flops of column solves, Eigen's simplicial float Cholesky above 40k tets);
// --huge: also the 300k-tet shell and the sixth sphere refinement. Scenes by name: shell10k,
// shell100k,
#include "Comparison/TraditionalBandSolve.h"
#include "Report/Report.h"

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

using namespace faceplan;
using namespace faceplan::report;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty())
      out.push_back(item);
  return out;
}

} // namespace

int main(int argc, char** argv) {
  Config cfg;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", key.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (key == "--out")
      cfg.outDir = value();
    else if (key == "--data")
      cfg.dataDir = value();
    else if (key == "--quick")
      cfg.quick = true;
    else if (key == "--large")
      cfg.large = true;
    else if (key == "--huge")
      cfg.huge = true;
    else if (key == "--no-ccx")
      cfg.ccx = false;
    else if (key == "--edits")
      cfg.edits = std::max(1, std::stoi(value()));
    else if (key == "--repeats")
      cfg.repeats = std::max(1, std::stoi(value()));
    else if (key == "--scenes")
      cfg.scenes = Split(value());
    else if (key == "--band-max-gflop")
      cfg.bandMaxGflop = std::stod(value());
    else if (key == "--help" || key == "-h") {
      std::printf("faceplan_report [--out DIR] [--data DIR] [--quick] [--large] [--huge] "
                  "[--no-ccx] [--edits N]\n"
                  "                [--repeats N] [--scenes a,b,...] [--band-max-gflop X]\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown option %s (try --help)\n", key.c_str());
      return 2;
    }
  }
  if (cfg.huge)
    cfg.large = true;
  if (cfg.dataDir.empty()) {
    // The source tree's Data/, found relative to the working directory or the executable.
    for (fs::path p : {fs::path("Data"), fs::path(argv[0]).parent_path() / "../../Data",
                       fs::path(argv[0]).parent_path() / "../Data"})
      if (fs::exists(p / "organs")) {
        cfg.dataDir = p.string();
        break;
      }
  }
  if (cfg.scenes.empty()) {
    if (cfg.quick)
      cfg.scenes = {"shell2k", "sphere1", "sphere2", "sphere3", "kidney", "mandible"};
    else {
      cfg.scenes = {"shell10k", "shell100k", "sphere1", "sphere2",  "sphere3",
                    "sphere4",  "kidney",    "heart",   "mandible", "face"};
      if (cfg.large)
        cfg.scenes.push_back("sphere5");
      if (cfg.huge)
        cfg.scenes.push_back("sphere6");
      if (cfg.huge)
        cfg.scenes.push_back("shell300k");
    }
  }
  const std::map<std::string, std::pair<int, int>> shells = {
      {"shell2k", {4, 2}}, {"shell10k", {8, 3}}, {"shell100k", {18, 5}}, {"shell300k", {30, 6}}};
  const std::map<std::string, std::pair<std::string, bool>> data = {
      {"kidney", {"organs/kidney_1900.vtu", false}},
      {"heart", {"organs/heart_6600.vtu", false}},
      {"mandible", {"organs/mandible_10600.vtu", false}},
      {"face", {"face/face_tissue.vtu", true}}};

  Report report(cfg);
  std::string lapackWhy;
  if (!BandLapackAvailable(&lapackWhy))
    std::printf("note: %s\n", lapackWhy.c_str());
  for (const std::string& name : cfg.scenes) {
    Scene scene;
    if (shells.count(name)) {
      scene = FaceLikeShell(name, shells.at(name).first, shells.at(name).second);
    } else if (name.rfind("sphere", 0) == 0 && name.size() > 6) {
      scene = Sphere(std::stoi(name.substr(6)));
    } else if (data.count(name)) {
      std::string error;
      if (cfg.dataDir.empty() ||
          !DataScene(name, (fs::path(cfg.dataDir) / data.at(name).first).string(),
                     data.at(name).second, scene, error)) {
        std::fprintf(stderr, "skipping %s: %s\n", name.c_str(),
                     cfg.dataDir.empty() ? "Data/ not found (--data)" : error.c_str());
        continue;
      }
    } else {
      std::fprintf(stderr, "unknown scene %s\n", name.c_str());
      return 2;
    }
    report.run(scene);
    report.write(); // after every scene, so an interrupted run still leaves its results
  }
  std::printf("\nwrote %s/results.csv, table2.csv, REPORT.md\n", cfg.outDir.c_str());
  return 0;
}