// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Command-line options and scene shared by the benchmark programs that time one stage on
// MakeFaceLikeScene(subdivisions, layers): --subdivisions S --layers L --repeats R.
#include "CondensedFEM/CondensedFEM.h"
#include "Support/FEMTestScenes.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace faceplan::benchmarks {

struct SceneArguments {
  int subdivisions = 18, layers = 5, repeats = 3;
};

// Fills `args` (its values are the defaults); false, after printing the usage, on an unknown
// option.
inline bool ParseSceneArguments(int argc, char** argv, SceneArguments& args) {
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--subdivisions"))
      args.subdivisions = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--layers"))
      args.layers = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--repeats"))
      args.repeats = std::max(1, std::atoi(argv[i + 1]));
    else {
      std::fprintf(stderr, "usage: %s [--subdivisions S] [--layers L] [--repeats R]\n", argv[0]);
      return false;
    }
  }
  return true;
}

// The scene's precompute request, dense response asked for (what faceplan_benchmark times).
inline PrecomputeRequest DenseResponseScene(const SceneArguments& args) {
  PrecomputeRequest request = testing::ShellRequest(args.subdivisions, args.layers);
  request.options.method = SolveMethod::DenseResponse;
  return request;
}

} // namespace faceplan::benchmarks
